#include "sim/forward_model.hpp"

#include <algorithm>
#include <cmath>
#include <random>

#include "imaging/frame_conversion.hpp"
#include "imaging/motion_frame.hpp"
#include "sim/pixel_integration.hpp"

namespace flutterscan::sim {
using imaging::Plane;

imaging::Image expected_electrons(const Plane& reflectance, const imaging::CaptureModel& model,
                                  int supersample) {
  const Plane moving = imaging::to_motion_frame(reflectance, model.direction);
  imaging::CaptureModel fine = rendered_pixels(model);
  fine.blur_px = model.blur_px * supersample;
  imaging::Image out;
  for (int c = 0; c < model.channels; ++c)
    out.channels.push_back(imaging::from_motion_frame(
        blur_and_bin_rows(moving, imaging::channel_psf(fine, c), supersample), model.direction));
  return out;
}

imaging::Image record_frame(const imaging::Image& expected, const imaging::CaptureModel& model,
                            std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> read(0.0, model.read_noise);
  const double full_scale = std::pow(2.0, model.bit_depth) - 1.0;
  auto record = [&](double electrons) {
    const double mean = std::max(0.0, electrons);
    double e =
        mean > 0 ? static_cast<double>(std::poisson_distribution<long long>(mean)(rng)) : 0.0;
    e = std::min(e, model.full_well) + (model.read_noise > 0 ? read(rng) : 0.0);
    double dn = std::clamp(std::round(e / model.gain + model.black_level), 0.0, full_scale);
    if (model.encoding != imaging::Encoding::kLinear) {
      const double unit = dn / full_scale;
      dn = std::round(full_scale * (model.encoding == imaging::Encoding::kSrgb
                                        ? imaging::linear_to_srgb(unit)
                                        : std::pow(unit, 1.0 / model.gamma)));
    }
    return static_cast<float>(dn);
  };
  imaging::Image out;
  if (model.bayer_rggb) {
    const int w = expected.width(), h = expected.height();
    Plane mosaic(w, h);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const int channel = (y % 2 == 0) ? (x % 2 == 0 ? 0 : 1) : (x % 2 == 0 ? 1 : 2);
        mosaic.at(x, y) = record(expected.channels[static_cast<std::size_t>(channel)].at(x, y));
      }
    out.channels.push_back(std::move(mosaic));
    return out;
  }
  for (const Plane& plane : expected.channels) {
    Plane dn(plane.width, plane.height);
    for (std::size_t i = 0; i < plane.pixels.size(); ++i) dn.pixels[i] = record(plane.pixels[i]);
    out.channels.push_back(std::move(dn));
  }
  return out;
}

}  // namespace flutterscan::sim
