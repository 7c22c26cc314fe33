// libFuzzer target: a capture descriptor (JSON, docs/formats.md) with a small
// frame through `flutterscan deblur`'s whole path: from_descriptor, the DN to
// electrons conversion, deblur (or deblur_bayer for a Bayer descriptor).
//
// Input: byte 0 picks the method (bits 0-1) and the Bayer mode (bit 2); the rest
// is the descriptor's text. The frame is 48 x 24 px (a few bars and a ramp) with
// the descriptor's channel count.
// Oracles: a refused descriptor or deblur names what is wrong (a message); a
// deblurred frame is the frame's size and finite everywhere.

#include <nlohmann/json.hpp>

#include <cmath>

#include "fuzz_support.hpp"
#include "imaging/bayer.hpp"
#include "imaging/capture_descriptor.hpp"
#include "imaging/deblur.hpp"
#include "imaging/frame_conversion.hpp"

using namespace flutterscan;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1 || size > 16 * 1024) return 0;
  const std::uint8_t mode = data[0];
  const auto json = nlohmann::json::parse(data + 1, data + size, nullptr, false);
  if (json.is_discarded()) return 0;
  auto model = imaging::from_descriptor(json);
  if (!model.ok()) {
    fuzz::trace("descriptor refused: " + model.error());
    FUZZ_CHECK(!model.error().empty(), "a refused descriptor without a message");
    return 0;
  }
  const imaging::CaptureModel& m = model.value();
  constexpr int kWidth = 48, kHeight = 24;
  imaging::Image dn;
  const int planes = m.bayer_rggb ? 1 : m.channels;
  for (int c = 0; c < planes && c < 4; ++c) {
    imaging::Plane plane(kWidth, kHeight);
    for (int y = 0; y < kHeight; ++y)
      for (int x = 0; x < kWidth; ++x)
        plane.at(x, y) = static_cast<float>(((x / 6 + y / 8 + c) % 2) * 900 + 40 + x * 3);
    dn.channels.push_back(std::move(plane));
  }
  if (dn.channels.empty()) return 0;
  imaging::DeblurOptions options;
  static constexpr imaging::Method kMethods[] = {
      imaging::Method::kJointWiener, imaging::Method::kWienerAverage,
      imaging::Method::kRichardsonLucy, imaging::Method::kTotalVariation};
  options.method = kMethods[mode & 3];
  options.iterations = 3;  // a fixed, short run: the path, not the convergence
  options.threads = 1;
  const imaging::Image electrons = imaging::dn_to_electrons(dn, m);
  using Deblurred = Result<imaging::DeblurResult, std::string>;
  const Deblurred result = [&] {
    if (!m.bayer_rggb) return imaging::deblur(electrons, m, options);
    auto bayer = imaging::deblur_bayer(
        electrons.channels[0], m, options,
        (mode & 4) != 0 ? imaging::BayerMode::kDemosaicFirst : imaging::BayerMode::kRawPlanes);
    if (!bayer.ok()) return Deblurred::failure(bayer.error());
    return Deblurred::success(std::move(bayer.value()));
  }();
  if (!result.ok()) {
    fuzz::trace("deblur refused: " + result.error());
    FUZZ_CHECK(!result.error().empty(), "a refused deblur without a message");
    return 0;
  }
  const imaging::Plane& latent = result.value().latent;
  fuzz::trace("deblurred, blur " + std::to_string(m.blur_px));
  FUZZ_CHECK(latent.width == kWidth && latent.height == kHeight,
             "latent " + std::to_string(latent.width) + " x " + std::to_string(latent.height));
  for (float v : latent.pixels)
    FUZZ_CHECK(std::isfinite(v),
               "a deblurred pixel is not finite (blur " + std::to_string(m.blur_px) + ")");
  return 0;
}
