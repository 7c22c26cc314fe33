// ZXing 1.4 returns UTF-8 std::string from Result::text() only with ZX_USE_UTF8.
#define ZX_USE_UTF8 1

#include "session/barcode_reader.hpp"

#include "session/assertion_guard.hpp"

#include <ZXing/BarcodeFormat.h>
#include <ZXing/DecodeHints.h>
#include <ZXing/ImageView.h>
#include <ZXing/ReadBarcode.h>
#include <ZXing/Result.h>

#include <algorithm>
#include <cstdint>
#include <stdexcept>

namespace flutterscan::session {

std::string check_symbologies(const std::string& symbologies) {
  try {
    if (ZXing::BarcodeFormatsFromString(symbologies).empty()) return "names no symbology";
  } catch (const std::exception& e) {
    return e.what();
  }
  return {};
}

BarcodeReadout read_barcodes(const imaging::Plane& latent, const std::string& symbologies,
                             bool try_rotate) {
  BarcodeReadout out;
  if (latent.empty()) return out;
  std::vector<std::uint8_t> lum(latent.pixels.size());
  std::transform(latent.pixels.begin(), latent.pixels.end(), lum.begin(), [](float v) {
    return static_cast<std::uint8_t>(std::clamp(v, 0.0f, 1.0f) * 255.0f + 0.5f);
  });
  const ZXing::ImageView view(lum.data(), latent.width, latent.height, ZXing::ImageFormat::Lum);
  ZXing::DecodeHints hints;
  hints.setFormats(ZXing::BarcodeFormatsFromString(symbologies))
      .setTryHarder(true)
      .setTryRotate(try_rotate);
  ZXing::Results results;
  out.decoder_fault = run_catching_assertions([&] { results = ZXing::ReadBarcodes(view, hints); });
  if (!out.decoder_fault.empty()) return out;
  for (const ZXing::Result& result : results) {
    if (!result.isValid()) continue;
    DecodedCode code;
    code.text = result.text();
    code.format = ZXing::ToString(result.format());
    const auto& p = result.position();
    double sx = 0, sy = 0;
    code.min_x = p[0].x;
    code.max_x = p[0].x;
    for (int i = 0; i < 4; ++i) {
      sx += p[i].x;
      sy += p[i].y;
      code.min_x = std::min<double>(code.min_x, p[i].x);
      code.max_x = std::max<double>(code.max_x, p[i].x);
    }
    code.centre_x = sx / 4;
    code.centre_y = sy / 4;
    out.codes.push_back(std::move(code));
  }
  return out;
}

std::vector<LabelRegion> find_label_regions(const imaging::Plane& latent, double paper_threshold,
                                            double min_fraction, int min_width, int max_gap) {
  std::vector<LabelRegion> regions;
  if (latent.empty()) return regions;
  std::vector<int> bright(static_cast<std::size_t>(latent.width), 0);
  for (int y = 0; y < latent.height; ++y) {
    const auto row = latent.row(y);
    for (int x = 0; x < latent.width; ++x) bright[x] += row[x] > paper_threshold ? 1 : 0;
  }
  const int need = std::max(1, static_cast<int>(min_fraction * latent.height));
  // Runs of bright columns, with gaps up to max_gap closed (dark bars inside a label).
  std::vector<LabelRegion> runs;
  int start = -1;
  for (int x = 0; x <= latent.width; ++x) {
    const bool on = x < latent.width && bright[x] >= need;
    if (on && start < 0) start = x;
    if (!on && start >= 0) {
      if (!runs.empty() && start - runs.back().end <= max_gap)
        runs.back().end = x;
      else
        runs.push_back({start, x});
      start = -1;
    }
  }
  for (const auto& run : runs)
    if (run.end - run.begin >= min_width && run.begin > 0 && run.end < latent.width)
      regions.push_back(run);
  return regions;
}

}  // namespace flutterscan::session
