// ZXing 1.4 returns UTF-8 std::string from Result::text() only with ZX_USE_UTF8.
#define ZX_USE_UTF8 1

#include "reader/read_evidence.hpp"

#include <ZXing/ImageView.h>
#include <ZXing/ReadBarcode.h>
#include <ZXing/Result.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <vector>

#include "reader/assertion_guard.hpp"
#include "reader/ean_upc_layout.hpp"
#include "reader/zbar_reader.hpp"

namespace flutterscan::reader {
namespace {

bool same_value(const std::string& text, const std::string& format, const DecodedCode& code) {
  return text == code.text && symbology_family(format) == symbology_family(code.format);
}

/// Whether ZXing (`hints`) reads `code`'s value in `view`.
bool zxing_reads(const ZXing::ImageView& view, const ZXing::DecodeHints& hints,
                 const DecodedCode& code) {
  ZXing::Results results;
  const std::string fault =
      run_catching_assertions([&] { results = ZXing::ReadBarcodes(view, hints); });
  return fault.empty() && std::any_of(results.begin(), results.end(), [&](const auto& r) {
           return r.isValid() && same_value(r.text(), ZXing::ToString(r.format()), code);
         });
}

/// Whether zbar reads `code`'s value in the packed luminance `lum`.
bool zbar_reads(std::span<const std::uint8_t> lum, int width, int height,
                const std::string& symbologies, bool try_rotate, const DecodedCode& code) {
  const std::vector<ZbarSymbol> symbols = zbar_read(lum, width, height, symbologies, try_rotate);
  return std::any_of(symbols.begin(), symbols.end(),
                     [&](const ZbarSymbol& s) { return same_value(s.text, s.format, code); });
}

/// Columns [x0, x1) of rows [y0, y1) of `lum` (packed rows of `width`), packed.
std::vector<std::uint8_t> cropped(std::span<const std::uint8_t> lum, int width, int x0, int y0,
                                  int x1, int y1) {
  std::vector<std::uint8_t> out;
  out.reserve(static_cast<std::size_t>(x1 - x0) * static_cast<std::size_t>(y1 - y0));
  for (int y = y0; y < y1; ++y) {
    const auto row = lum.begin() + static_cast<std::ptrdiff_t>(y) * width;
    out.insert(out.end(), row + x0, row + x1);
  }
  return out;
}

/// A window cut down to a symbol's surroundings: its own copies of the rows,
/// which `window`'s spans view (moving the struct moves the vectors' buffers
/// with them, so the spans stay valid; a copy would not).
struct Surroundings {
  std::vector<std::uint8_t> lum, zbar_lum;
  LumWindow window;
};

/// `window` cut to `code`'s surroundings: the box of its corners and its
/// extent along x, widened along its reading direction by a quarter of its
/// length each way (every symbology's quiet zone, 7 to 11 modules, is less)
/// and across its bars by half its length each way (a linear symbol's bars are
/// taller than the rows that read it; each half then still holds its bars).
/// A second reading of the symbol needs no more of the window; the rest is
/// other print, which costs a decoder time and is no evidence of this symbol.
Surroundings surroundings(const DecodedCode& code, const LumWindow& window, bool along_x) {
  double left = code.min_x, right = code.max_x, top = code.centre_y, bottom = code.centre_y;
  for (const CodePoint& p : code.quality.corners) {
    left = std::min(left, p.x);
    right = std::max(right, p.x);
    top = std::min(top, p.y);
    bottom = std::max(bottom, p.y);
  }
  const double length = along_x ? right - left : bottom - top;
  const double along_margin = std::max(16.0, length / 4),
               across_margin = std::max(16.0, length / 2);
  const double margin_x = along_x ? along_margin : across_margin;
  const double margin_y = along_x ? across_margin : along_margin;
  auto clip = [](double v, int size) {
    return std::clamp(static_cast<int>(std::lround(v)), 0, size);
  };
  const int x0 = clip(left - margin_x - window.x0, window.width),
            x1 = clip(right + margin_x - window.x0, window.width),
            y0 = clip(top - margin_y - window.y0, window.height),
            y1 = clip(bottom + margin_y - window.y0, window.height);
  Surroundings out;
  out.lum = cropped(window.lum, window.width, x0, y0, x1, y1);
  if (!window.zbar_lum.empty())
    out.zbar_lum = cropped(window.zbar_lum, window.width, x0, y0, x1, y1);
  out.window = {out.lum, x1 - x0, y1 - y0, window.x0 + x0, window.y0 + y0, out.zbar_lum};
  return out;
}

}  // namespace

bool weak_check(const std::string& format) {
  static const std::array<std::string, 7> kWeak = {"EAN-13", "EAN-8",  "UPC-A",  "UPC-E",
                                                   "ITF",    "Code39", "Codabar"};
  return std::find(kWeak.begin(), kWeak.end(), format) != kWeak.end();
}

bool no_check(const std::string& format) {
  return format == "ITF" || format == "Code39" || format == "Codabar";
}

std::string symbology_family(const std::string& format) {
  if (is_ean_upc(format)) return "EAN/UPC";
  return format;
}

std::string corroboration(const DecodedCode& code, const LumWindow& whole,
                          const ZXing::DecodeHints& hints, const std::string& symbologies,
                          bool try_rotate, int independent_apart) {
  const double turn = code.orientation_deg * std::numbers::pi / 180;
  const bool along_x = std::abs(std::cos(turn)) >= std::abs(std::sin(turn));
  const Surroundings near = surroundings(code, whole, along_x);
  const LumWindow& window = near.window;
  // The symbol's centre across its bars, in the window: the halves meet there.
  const int across = along_x ? window.height : window.width;
  const int cut = static_cast<int>(
      std::lround(along_x ? code.centre_y - window.y0 : code.centre_x - window.x0));
  const bool zxing = code.decoder == "zxing";
  // Left out at the cut: the rows that share samples with rows across it.
  const int gap = std::max(0, independent_apart - 1);
  const int end_a = cut - gap / 2, begin_b = cut + (gap - gap / 2);
  // Halves rule out noise only: no halves for a symbology with no check at all.
  if (!no_check(code.format) && independent_apart > 0 && end_a > 0 && begin_b < across) {
    bool both = true;
    for (const auto& [from, to] : {std::pair{0, end_a}, std::pair{begin_b, across}}) {
      const int w = along_x ? window.width : to - from, h = along_x ? to - from : window.height;
      const std::vector<std::uint8_t> half =
          along_x ? cropped(window.lum, window.width, 0, from, window.width, to)
                  : cropped(window.lum, window.width, from, 0, to, window.height);
      const bool reads =
          zxing ? zxing_reads(ZXing::ImageView(half.data(), w, h, ZXing::ImageFormat::Lum), hints,
                              code)
                : zbar_reads(half, w, h, symbologies, try_rotate, code);
      if (!reads) {
        both = false;
        break;
      }
    }
    if (both) return "halves";
  }
  if (zxing)
    for (const auto lum : {window.lum, window.zbar_lum})
      if (!lum.empty() &&
          zbar_reads(lum, window.width, window.height, symbologies, try_rotate, code))
        return "decoders";
  return "";
}

}  // namespace flutterscan::reader
