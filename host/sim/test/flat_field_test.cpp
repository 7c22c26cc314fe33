// The flat field: measured from white-target frames under light that varies
// across the field of view, it recovers the variation, and applying it makes a
// label under that light deblur as well as under uniform light.

#include <gtest/gtest.h>

#include "imaging/deblur.hpp"
#include "imaging/flat_field.hpp"
#include "imaging/frame_conversion.hpp"
#include "imaging/metrics.hpp"
#include "imaging/test/label_capture.hpp"
#include "sim/forward_model.hpp"
#include "sim/scene.hpp"

namespace flutterscan::sim {
namespace {

using imaging::CaptureModel;
using imaging::Image;
using imaging::Plane;

using test_fixtures::kFoundMse;

CaptureModel capture(const std::string& code, double electrons) {
  return test_fixtures::label_capture({.code = code.c_str(),
                                       .blur_px = code.size() == 52 && code[0] == '4' ? 52.0 : 1.0,
                                       .electrons = electrons,
                                       .black_level = 64});
}

/// LED k's relative illumination at (x, y): linear ramps with median 1, different per LED.
double illumination(int k, int x, int y, int width, int height) {
  const double u = (x + 0.5) / width - 0.5, v = (y + 0.5) / height - 0.5;
  const double along[3] = {0.4, -0.3, 0.2}, across[3] = {0.1, 0.3, -0.4};
  return 1 + along[k] * u + across[k] * v;
}

/// Expected electrons of `scene` under `m` with each LED's light scaled per pixel
/// (`vary`), or uniform.
Image expected_under(const Plane& scene, const CaptureModel& m, bool vary) {
  Image total;
  for (int k = 0; k < 3; ++k) {
    CaptureModel alone = m;
    for (int j = 0; j < 3; ++j)
      if (j != k) alone.led_electrons[static_cast<std::size_t>(j)] = 0;
    const Image part = expected_electrons(scene, alone);
    if (total.channels.empty()) {
      total = part;
      for (auto& p : total.channels) std::fill(p.pixels.begin(), p.pixels.end(), 0.0f);
    }
    for (int c = 0; c < 3; ++c)
      for (int y = 0; y < scene.height; ++y)
        for (int x = 0; x < scene.width; ++x)
          total.channels[static_cast<std::size_t>(c)].at(x, y) +=
              part.channels[static_cast<std::size_t>(c)].at(x, y) *
              static_cast<float>(vary ? illumination(k, x, y, scene.width, scene.height) : 1.0);
  }
  return total;
}

imaging::FlatField measured(int width, int height) {
  const Plane white(width, height, 0.9f);
  const CaptureModel dark_model = capture(std::string(52, '7'), 0);
  const Image dark = record_frame(expected_under(white, dark_model, true), dark_model, 1);
  std::vector<Image> lit;
  for (char digit : {'1', '2', '4'}) {
    const CaptureModel m = capture(std::string(52, digit), 3000);
    lit.push_back(
        record_frame(expected_under(white, m, true), m, static_cast<std::uint64_t>(digit)));
  }
  const auto flat = imaging::measure_flat_field(dark, lit, 8, 6, 4095);
  EXPECT_TRUE(flat.ok()) << flat.error();
  return flat.value();
}

TEST(FlatField, RecoversTheIlluminationOfEachLed) {
  const imaging::FlatField flat = measured(640, 360);
  ASSERT_EQ(flat.mixing.size(), 8u * 6u * 9u);
  for (int ty = 0; ty < 6; ++ty)
    for (int tx = 0; tx < 8; ++tx)
      for (int k = 0; k < 3; ++k) {
        const int x = 640 * tx / 8 + 40, y = 360 * ty / 6 + 30;  // tile centres
        const auto d = static_cast<std::size_t>(k * 3 + k);
        const double relative =
            flat.mixing[static_cast<std::size_t>(ty * 8 + tx) * 9 + d] / flat.reference[d];
        EXPECT_NEAR(relative, illumination(k, x, y, 640, 360), 0.02)
            << tx << "," << ty << " LED " << k;
      }
  EXPECT_GT(flat.largest_deviation, 0.2);
  // Round trip through its file format.
  const auto back = imaging::flat_field_from_json(imaging::flat_field_to_json(flat));
  ASSERT_TRUE(back.ok()) << back.error();
  EXPECT_EQ(back.value().mixing, flat.mixing);
  auto broken = imaging::flat_field_to_json(flat);
  broken["mixing_dn"].erase(0);
  EXPECT_FALSE(imaging::flat_field_from_json(broken).ok());
}

TEST(FlatField, CorrectedFramesDeblurLikeUniformLight) {
  SceneSpec spec;
  spec.kind = SceneKind::kCode128;
  spec.content = "FLAT-0042";
  const Plane scene = render_scene(spec).value();
  const CaptureModel m = capture(kFoundMse, 3000);
  imaging::DeblurOptions options;
  options.method = imaging::Method::kTotalVariation;
  const auto region = imaging::scored_region(scene.width, scene.height, m.blur_px, m.direction);
  auto score = [&](const Image& electrons) {
    const auto result = imaging::deblur(electrons, m, options);
    EXPECT_TRUE(result.ok());
    return imaging::psnr(scene, result.value().latent, region);
  };
  const Image uniform =
      imaging::dn_to_electrons(record_frame(expected_under(scene, m, false), m, 5), m);
  Image varying = imaging::dn_to_electrons(record_frame(expected_under(scene, m, true), m, 5), m);
  const double uniform_db = score(uniform);
  const double uncorrected_db = score(varying);
  ASSERT_EQ(imaging::apply_flat_field(varying, measured(640, 360)), "");
  const double corrected_db = score(varying);
  EXPECT_GT(corrected_db, uncorrected_db + 3) << "uncorrected " << uncorrected_db;
  EXPECT_GT(corrected_db, uniform_db - 1.5) << "uniform " << uniform_db;
  Image other_size;
  other_size.channels.assign(3, Plane(320, 180));
  EXPECT_NE(imaging::apply_flat_field(other_size, measured(640, 360)).find("640x360"),
            std::string::npos);
}

}  // namespace
}  // namespace flutterscan::sim
