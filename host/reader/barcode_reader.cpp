// ZXing 1.4 returns UTF-8 std::string from Result::text() only with ZX_USE_UTF8.
#define ZX_USE_UTF8 1

#include "reader/barcode_reader.hpp"

#include "imaging/bilinear.hpp"
#include "imaging/frame_conversion.hpp"
#include "imaging/motion_frame.hpp"
#include "reader/assertion_guard.hpp"
#include "reader/ean_upc_layout.hpp"
#include "reader/read_evidence.hpp"
#include "reader/zbar_reader.hpp"

#include <ZXing/BarcodeFormat.h>
#include <ZXing/DecodeHints.h>
#include <ZXing/ImageView.h>
#include <ZXing/ReadBarcode.h>
#include <ZXing/Result.h>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <utility>

namespace flutterscan::reader {

std::string check_symbologies(const std::string& symbologies) {
  try {
    if (ZXing::BarcodeFormatsFromString(symbologies).empty()) return "names no symbology";
  } catch (const std::exception& e) {
    return e.what();
  }
  return {};
}

namespace {

/// The linear (1-D) formats among `formats`.
ZXing::BarcodeFormats linear_formats(ZXing::BarcodeFormats formats) {
  return formats & ZXing::BarcodeFormats(ZXing::BarcodeFormat::LinearCodes);
}

}  // namespace

std::string linear_symbologies(const std::string& symbologies) {
  const ZXing::BarcodeFormats linear = linear_formats(ZXing::BarcodeFormatsFromString(symbologies));
  return linear.empty() ? std::string() : ZXing::ToString(linear);
}

bool names_symbology(const std::string& symbologies, const std::string& format) {
  return ZXing::BarcodeFormatsFromString(symbologies)
      .testFlag(ZXing::BarcodeFormatFromString(format));
}

namespace {

/// Reflectance 0..1 to sRGB-encoded 8-bit, in kSrgbSteps steps of linear light.
constexpr int kSrgbSteps = 16384;
const std::vector<std::uint8_t>& srgb_table() {
  static const std::vector<std::uint8_t> table = [] {
    std::vector<std::uint8_t> t(kSrgbSteps + 1);
    for (int i = 0; i <= kSrgbSteps; ++i)
      t[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(
          imaging::linear_to_srgb(static_cast<double>(i) / kSrgbSteps) * 255.0 + 0.5);
    return t;
  }();
  return table;
}

/// A linear symbol whose ends lie this close to its window's edge along its
/// reading direction is cut by it (cut_along_reading()).
constexpr int kEdgePx = 1;

/// Of the window's pixels, the share below which its black level lies: the
/// darkest print, less the few pixels noise pushes below it.
constexpr double kBlackShare = 0.01;
/// Steps of reflectance 0..1 the black level is found in.
constexpr int kBlackSteps = 1024;

/// The reflectance a share kBlackShare of the window's pixels lie below.
float black_level(const imaging::Plane& latent, int x0, int y0, int x1, int y1) {
  std::vector<int> histogram(kBlackSteps + 1, 0);
  for (int y = y0; y < y1; ++y) {
    const float* row = latent.row(y).data();
    for (int x = x0; x < x1; ++x)
      ++histogram[static_cast<std::size_t>(std::clamp(row[x], 0.0f, 1.0f) * kBlackSteps)];
  }
  const auto below = static_cast<long long>(kBlackShare * static_cast<double>(x1 - x0) *
                                            static_cast<double>(y1 - y0));
  long long seen = 0;
  for (int i = 0; i <= kBlackSteps; ++i) {
    seen += histogram[static_cast<std::size_t>(i)];
    if (seen > below) return static_cast<float>(i) / kBlackSteps;
  }
  return 1.0f;
}

/// The paper view's reach: the paper beside a pixel is the brightest pixel
/// within kPaperReachPx / 2 of it along its row (wider than a linear code's
/// widest bar, 4 modules, up to modules of about 7 px), averaged over a
/// kPaperReachPx square (a bar's middle, where the reach sees only ink, takes
/// the paper around it).
constexpr int kPaperReachPx = 31;
/// The least span from black to paper the paper view stretches: a flat dark
/// area is not made print.
constexpr float kLeastPaperSpan = 0.02f;

/// The paper beside each pixel of columns [x0, x1) of rows [y0, y1) (see kPaperReachPx).
cv::Mat paper_level(const imaging::Plane& latent, int x0, int y0, int x1, int y1) {
  const cv::Mat whole(latent.height, latent.width, CV_32F,
                      const_cast<float*>(latent.pixels.data()));
  cv::Mat window = whole(cv::Range(y0, y1), cv::Range(x0, x1)), brightest, paper;
  cv::dilate(window, brightest, cv::getStructuringElement(cv::MORPH_RECT, {kPaperReachPx, 1}),
             {-1, -1}, 1, cv::BORDER_REPLICATE);
  cv::blur(brightest, paper, {kPaperReachPx, kPaperReachPx}, {-1, -1}, cv::BORDER_REPLICATE);
  return paper;
}

/// The smoothed view's Gaussian, px: what a module's centre averages over. A
/// 2.5 px module (a QR code of 57 modules in 140 px) keeps its centre's value
/// against its neighbours', and the noise each sample carries falls by the
/// Gaussian's footprint (about 6 pixels).
constexpr double kModuleCentreSigmaPx = 0.7;

/// Columns [x0, x1) of rows [y0, y1) of `latent`, smoothed (kModuleCentreSigmaPx).
cv::Mat smoothed(const imaging::Plane& latent, int x0, int y0, int x1, int y1) {
  const cv::Mat whole(latent.height, latent.width, CV_32F,
                      const_cast<float*>(latent.pixels.data()));
  cv::Mat out;
  cv::GaussianBlur(whole(cv::Range(y0, y1), cv::Range(x0, x1)), out, {0, 0}, kModuleCentreSigmaPx,
                   kModuleCentreSigmaPx, cv::BORDER_REPLICATE);
  return out;
}

/// Columns [x0, x1) of rows [y0, y1) of `latent` into `lum` (rows of x1 - x0
/// bytes) as ZXing's 8-bit luminance: linear in reflectance, sRGB-encoded,
/// sRGB-encoded from the window's black level, from it to the paper, or
/// smoothed and encoded from it.
void to_luminance(const imaging::Plane& latent, int x0, int y0, int x1, int y1, LuminanceView view,
                  std::vector<std::uint8_t>& lum) {
  const auto width = static_cast<std::size_t>(x1 - x0);
  lum.resize(width * static_cast<std::size_t>(y1 - y0));
  const std::vector<std::uint8_t>& srgb = srgb_table();
  const bool from_black = view == LuminanceView::kSrgbFromBlack ||
                          view == LuminanceView::kSrgbToPaper ||
                          view == LuminanceView::kSmoothedFromBlack;
  const float black = from_black ? black_level(latent, x0, y0, x1, y1) : 0.0f;
  const float gain = black < 1.0f ? 1.0f / (1.0f - black) : 1.0f;
  const cv::Mat paper =
      view == LuminanceView::kSrgbToPaper ? paper_level(latent, x0, y0, x1, y1) : cv::Mat();
  const cv::Mat smooth =
      view == LuminanceView::kSmoothedFromBlack ? smoothed(latent, x0, y0, x1, y1) : cv::Mat();
  for (int y = y0; y < y1; ++y) {
    const float* row = smooth.empty() ? latent.row(y).data() + x0 : smooth.ptr<float>(y - y0);
    std::uint8_t* out = lum.data() + static_cast<std::size_t>(y - y0) * width;
    if (view == LuminanceView::kLinear) {
      for (std::size_t x = 0; x < width; ++x)
        out[x] = static_cast<std::uint8_t>(std::clamp(row[x], 0.0f, 1.0f) * 255.0f + 0.5f);
    } else if (view == LuminanceView::kSrgbToPaper) {
      const float* white = paper.ptr<float>(y - y0);
      for (std::size_t x = 0; x < width; ++x)
        out[x] = srgb[static_cast<std::size_t>(
            std::clamp((row[x] - black) / std::max(white[x] - black, kLeastPaperSpan), 0.0f, 1.0f) *
                kSrgbSteps +
            0.5f)];
    } else {
      for (std::size_t x = 0; x < width; ++x)
        out[x] = srgb[static_cast<std::size_t>(
            std::clamp((row[x] - black) * gain, 0.0f, 1.0f) * kSrgbSteps + 0.5f)];
    }
  }
}

/// The code ZXing read in a window at (offset_x, offset_y) of `latent`, measured on the latent.
DecodedCode decoded_code(const ZXing::Result& result, int offset_x, int offset_y,
                         const imaging::Plane& latent) {
  DecodedCode code;
  code.text = result.text();
  code.format = ZXing::ToString(result.format());
  code.symbology_id = result.symbologyIdentifier();
  code.ec_level = result.ecLevel();
  code.orientation_deg = result.orientation();
  const auto& p = result.position();
  CodeCorners corners;
  for (int i = 0; i < 4; ++i) corners[i] = {p[i].x + 0.0 + offset_x, p[i].y + 0.0 + offset_y};
  measure_and_place(code, latent, corners);
  return code;
}

/// The linear code zbar read in a window at (offset_x, offset_y) of `latent`,
/// measured on the latent. Its corners are the box of its scan lines' ends,
/// in ZXing's order (the top edge first, along the reading direction).
DecodedCode decoded_code(const ZbarSymbol& symbol, int offset_x, int offset_y,
                         const imaging::Plane& latent) {
  DecodedCode code;
  code.text = symbol.text;
  code.format = symbol.format;
  code.symbology_id = symbol.symbology_id;
  code.orientation_deg = symbol.along_x ? 0 : 90;
  code.luminance = LuminanceView::kSrgbFromBlack;
  code.decoder = "zbar";
  const double x0 = symbol.min_x + offset_x, x1 = symbol.max_x + offset_x;
  const double y0 = symbol.min_y + offset_y, y1 = symbol.max_y + offset_y;
  const CodeCorners corners = symbol.along_x
                                  ? CodeCorners{{{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}}}
                                  : CodeCorners{{{x1, y0}, {x1, y1}, {x0, y1}, {x0, y0}}};
  measure_and_place(code, latent, corners);
  return code;
}

/// Whether a linear symbol spanning [low, high] along its reading direction,
/// in a window `length` px along it, reaches the window's edge: its quiet
/// zone, and maybe its last modules, lay outside what the decoder saw, and a
/// symbol cut there can decode to another value that passes its check digit
/// (the sim session at nominal noise: an EAN-13 cut by the frame's last column
/// read 4000001979714 in one frame, its value 4000001979752 in the next two).
/// The rule for both decoders.
bool cut_along_reading(int low, int high, int length) {
  return low <= kEdgePx || high >= length - 1 - kEdgePx;
}

/// cut_along_reading() for symbol `result` ZXing read in a window `width` x `height` px.
bool cut_along_reading(const ZXing::Result& result, int width, int height) {
  if (!ZXing::BarcodeFormats(ZXing::BarcodeFormat::LinearCodes).testFlag(result.format()))
    return false;
  const double turn = result.orientation() * std::numbers::pi / 180;
  const bool along_x = std::abs(std::cos(turn)) >= std::abs(std::sin(turn));
  const auto& corners = result.position();
  const auto [low, high] = std::minmax_element(corners.begin(), corners.end(),
                                               [&](const ZXing::PointI& a, const ZXing::PointI& b) {
                                                 return along_x ? a.x < b.x : a.y < b.y;
                                               });
  return along_x ? cut_along_reading(low->x, high->x, width)
                 : cut_along_reading(low->y, high->y, height);
}

/// The symbols ZXing reads with `hints` in `lum` (`width` x `height`, 8 bits):
/// the linear ones, where `row_step` > 1, on every row_step-th row, and with
/// tryRotate every row_step-th column (a view of the columns as rows: no copy),
/// each placed in `lum`'s pixels.
ZXing::Results read_view(const std::vector<std::uint8_t>& lum, int width, int height,
                         const ZXing::DecodeHints& hints, int row_step) {
  const ZXing::ImageView view(lum.data(), width, height, ZXing::ImageFormat::Lum);
  const ZXing::BarcodeFormats linear = linear_formats(hints.formats());
  if (row_step <= 1 || linear.empty()) return ZXing::ReadBarcodes(view, hints);
  ZXing::DecodeHints matrix_hints = hints;
  matrix_hints.setFormats(hints.formats() &
                          ZXing::BarcodeFormats(ZXing::BarcodeFormat::MatrixCodes));
  ZXing::Results out;
  if (!matrix_hints.formats().empty()) out = ZXing::ReadBarcodes(view, matrix_hints);
  // Not downscaled: ZXing's smaller copies would average rows row_step apart,
  // across a leaning code's bars.
  ZXing::DecodeHints linear_hints = hints;
  linear_hints.setFormats(linear).setTryRotate(false).setTryDownscale(false);
  const int rows = (height - 1) / row_step + 1, columns = (width - 1) / row_step + 1;
  const ZXing::ImageView every_nth_row(lum.data(), width, rows, ZXing::ImageFormat::Lum,
                                       width * row_step, 1);
  for (ZXing::Result& r : ZXing::ReadBarcodes(every_nth_row, linear_hints)) {
    ZXing::Position p = r.position();
    for (ZXing::PointI& corner : p) corner.y *= row_step;
    r.setPosition(p);
    out.push_back(std::move(r));
  }
  if (!hints.tryRotate()) return out;
  // The window mirrored about its diagonal: (u, v) is pixel (v * row_step, u).
  const ZXing::ImageView every_nth_column(lum.data(), height, columns, ZXing::ImageFormat::Lum,
                                          row_step, width);
  for (ZXing::Result& r : ZXing::ReadBarcodes(every_nth_column, linear_hints)) {
    const ZXing::Position& q = r.position();
    ZXing::Position p;
    for (int i = 0; i < 4; ++i) p[i] = {q[i].y * row_step, q[i].x};
    r.setPosition(p);
    out.push_back(std::move(r));
  }
  return out;
}

/// Whether `code` (read in `window`) is backed: a strong check, or for a
/// weak-check symbology a second reading (corroboration()); `code.evidence`
/// says which. A value nothing backs joins `unconfirmed` (once).
bool backed(DecodedCode& code, const LumWindow& window, int independent_apart,
            const ZXing::DecodeHints& linear_hints, const std::string& symbologies, bool try_rotate,
            std::vector<DecodedCode>& unconfirmed) {
  code.evidence = weak_check(code.format) ? corroboration(code, window, linear_hints, symbologies,
                                                          try_rotate, independent_apart)
                                          : "check";
  if (!code.evidence.empty()) return true;
  if (std::none_of(unconfirmed.begin(), unconfirmed.end(),
                   [&](const DecodedCode& c) { return same_symbol(c, code); }))
    unconfirmed.push_back(code);
  return false;
}

/// Windows may overlap: a symbol in two of them is one symbol.
bool already_read(const std::vector<DecodedCode>& codes, const DecodedCode& code) {
  return std::any_of(codes.begin(), codes.end(),
                     [&](const DecodedCode& c) { return same_symbol(c, code); });
}

}  // namespace

std::string luminance_view_name(LuminanceView view) {
  switch (view) {
    case LuminanceView::kLinear:
      return "linear";
    case LuminanceView::kSrgb:
      return "srgb";
    case LuminanceView::kSrgbFromBlack:
      return "srgb-from-black";
    case LuminanceView::kSrgbToPaper:
      return "srgb-to-paper";
    case LuminanceView::kSmoothedFromBlack:
      return "smoothed-from-black";
  }
  return "linear";
}

std::pair<double, double> corner_rows(const DecodedCode& code) {
  double y0 = code.quality.corners[0].y, y1 = y0;
  for (const CodePoint& p : code.quality.corners) {
    y0 = std::min(y0, p.y);
    y1 = std::max(y1, p.y);
  }
  return {y0, y1};
}

bool same_symbol(const DecodedCode& a, const DecodedCode& b) {
  // Whether (x, y) lies within `code`'s corners' bounding box widened by 4 px.
  auto within = [](const DecodedCode& code, double x, double y) {
    const auto [y0, y1] = corner_rows(code);
    return x > code.min_x - 4 && x < code.max_x + 4 && y > y0 - 4 && y < y1 + 4;
  };
  const bool near = std::abs(a.centre_x - b.centre_x) < 4 && std::abs(a.centre_y - b.centre_y) < 4;
  return a.text == b.text && a.format == b.format &&
         (near || (within(a, b.centre_x, b.centre_y) && within(b, a.centre_x, a.centre_y)));
}

BarcodeReadout read_barcodes(const imaging::Plane& latent, const std::string& symbologies,
                             bool try_rotate, std::span<const DecodeWindow> windows,
                             const DecodeBudget& budget) {
  BarcodeReadout out;
  if (latent.empty()) return out;
  const auto started = std::chrono::steady_clock::now();
  std::vector<std::uint8_t> lum;       // one window at a time
  std::vector<std::uint8_t> zbar_lum;  // the window in zbar's view, made where a read needs it
  ZXing::DecodeHints hints;
  hints.setFormats(ZXing::BarcodeFormatsFromString(symbologies))
      .setTryHarder(true)
      .setTryRotate(try_rotate);
  // The paper view is for linear codes: ZXing thresholds their rows by each
  // row's histogram, matrix codes by local blocks that the paper beside them
  // does not sway. The smoothed view is for matrix codes: a linear code's rows
  // are read along their whole length, which averages its noise already.
  const ZXing::BarcodeFormats linear = linear_formats(hints.formats());
  ZXing::DecodeHints linear_hints = hints;
  linear_hints.setFormats(linear);
  const ZXing::BarcodeFormats matrix =
      hints.formats() & ZXing::BarcodeFormats(ZXing::BarcodeFormat::MatrixCodes);
  ZXing::DecodeHints matrix_hints = hints;
  matrix_hints.setFormats(matrix);
  const DecodeWindow whole{0, 0, latent.width, latent.height};
  std::vector<std::array<int, 4>> reading;  // windows that read a code: x0, y0, x1, y1
  const std::span<const DecodeWindow> to_read =
      windows.empty() ? std::span<const DecodeWindow>(&whole, 1) : windows;
  // Whether one more view of `px` pixels would end past the deadline, or
  // (`within_budget`) the budget is spent.
  auto spent = [&](long long px, bool within_budget = true) {
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - started)
            .count();
    if (budget.deadline_ms >= 0 &&
        ms + budget.view_ms_per_mpx * static_cast<double>(px) * 1e-6 > budget.deadline_ms)
      return true;
    return within_budget && budget.ms > 0 && ms >= budget.ms;
  };
  bool started_any = false;
  for (std::size_t i = 0; i < to_read.size(); ++i) {
    const DecodeWindow& w = to_read[i];
    const int x0 = std::clamp(w.x, 0, latent.width), y0 = std::clamp(w.y, 0, latent.height);
    const int x1 = std::clamp(w.x + w.width, x0, latent.width),
              y1 = std::clamp(w.y + w.height, y0, latent.height);
    const long long area = static_cast<long long>(x1 - x0) * (y1 - y0);
    if (spent(area, started_any)) {
      out.windows_left.push_back(i);
      continue;
    }
    if (x1 - x0 < 1 || y1 - y0 < 1) continue;
    started_any = true;
    zbar_lum.clear();
    // A window mostly inside one that read a code is there for what that one
    // missed: read again, the same label cost a whole decode (a code region on
    // its label's paper reaches a little past the paper's window). One that
    // reaches well beyond (another label, a whole carton) is read.
    if (std::any_of(reading.begin(), reading.end(), [&](const std::array<int, 4>& r) {
          const long long across = std::max(0, std::min(x1, r[2]) - std::max(x0, r[0]));
          const long long h = std::max(0, std::min(y1, r[3]) - std::max(y0, r[1]));
          return 4 * across * h >= 3 * area;
        })) {
      ++out.windows_skipped;
      continue;
    }
    // The linear view first; a window it reads nothing in, again sRGB-encoded,
    // again from its black level, its linear codes again to the paper and its
    // matrix codes again smoothed.
    constexpr std::array<LuminanceView, kLuminanceViews> kViews = {
        LuminanceView::kLinear, LuminanceView::kSrgb, LuminanceView::kSrgbFromBlack,
        LuminanceView::kSrgbToPaper, LuminanceView::kSmoothedFromBlack};
    bool window_read = false, cut = false;
    for (int v = 0; v < std::min(w.views, kLuminanceViews); ++v) {
      if (v > 0 && spent(area)) {
        cut = true;
        break;
      }
      const LuminanceView luminance = kViews[static_cast<std::size_t>(v)];
      const bool to_paper = luminance == LuminanceView::kSrgbToPaper;
      const bool smooth = luminance == LuminanceView::kSmoothedFromBlack;
      if ((to_paper && linear.empty()) || (smooth && matrix.empty())) continue;
      const ZXing::DecodeHints& view_hints =
          to_paper ? linear_hints : (smooth ? matrix_hints : hints);
      const auto view_started = std::chrono::steady_clock::now();
      to_luminance(latent, x0, y0, x1, y1, luminance, lum);
      ZXing::Results results;
      out.decoder_fault = run_catching_assertions(
          [&] { results = read_view(lum, x1 - x0, y1 - y0, view_hints, w.linear_row_step); });
      if (v == 0 && w.linear_row_step <= 1) {
        out.first_view_ms += std::chrono::duration<double, std::milli>(
                                 std::chrono::steady_clock::now() - view_started)
                                 .count();
        out.first_view_px += area;
      }
      if (!out.decoder_fault.empty()) {
        // ZXing 1.4 fails an assertion comparing two equal linear symbols in one
        // image (Result::operator==: a label that repeats its barcode): the
        // window once more, stopping at its first symbol, reads one of them.
        ZXing::DecodeHints first_symbol = view_hints;
        first_symbol.setMaxNumberOfSymbols(1);
        out.decoder_fault = run_catching_assertions(
            [&] { results = read_view(lum, x1 - x0, y1 - y0, first_symbol, w.linear_row_step); });
      }
      if (!out.decoder_fault.empty()) {
        out.codes.clear();
        return out;
      }
      bool any = false;
      for (const ZXing::Result& result : results) {
        if (!result.isValid() || cut_along_reading(result, x1 - x0, y1 - y0)) continue;
        DecodedCode code = decoded_code(result, x0, y0, latent);
        code.luminance = luminance;
        if (weak_check(code.format) && luminance != LuminanceView::kSrgbFromBlack &&
            zbar_lum.empty())
          to_luminance(latent, x0, y0, x1, y1, LuminanceView::kSrgbFromBlack, zbar_lum);
        if (!backed(code, {lum, x1 - x0, y1 - y0, x0, y0, zbar_lum}, w.independent_apart,
                    linear_hints, symbologies, try_rotate, out.unconfirmed))
          continue;
        any = true;
        if (!already_read(out.codes, code)) out.codes.push_back(std::move(code));
      }
      if (any) {
        reading.push_back({x0, y0, x1, y1});
        window_read = true;
        break;
      }
    }
    // Cut short by the budget with nothing read (its views, or zbar's turn): left.
    if (!window_read && (cut || (w.second_decoder && !linear.empty() &&
                                 w.views >= kLuminanceViews && spent(area)))) {
      out.windows_cut.push_back(i);
      continue;
    }
    // Read nothing in every view: zbar, for the linear codes, finds a row's
    // edges where ZXing's one threshold per row found none.
    if (window_read || linear.empty() || w.views < kLuminanceViews || !w.second_decoder) continue;
    to_luminance(latent, x0, y0, x1, y1, LuminanceView::kSrgbFromBlack, lum);
    bool any = false;
    for (const ZbarSymbol& symbol : zbar_read(lum, x1 - x0, y1 - y0, symbologies, try_rotate)) {
      if (symbol.along_x ? cut_along_reading(symbol.min_x, symbol.max_x, x1 - x0)
                         : cut_along_reading(symbol.min_y, symbol.max_y, y1 - y0))
        continue;
      DecodedCode code = decoded_code(symbol, x0, y0, latent);
      if (!quiet_zones_clear(code, latent) ||
          !backed(code, {lum, x1 - x0, y1 - y0, x0, y0, {}}, w.independent_apart, linear_hints,
                  symbologies, try_rotate, out.unconfirmed))
        continue;
      any = true;
      if (!already_read(out.codes, code)) out.codes.push_back(std::move(code));
    }
    if (any) reading.push_back({x0, y0, x1, y1});
  }
  drop_conflicting(out.codes);
  return out;
}

BarcodeReadout read_barcodes_turned(const imaging::Plane& latent, const DecodeWindow& window,
                                    double turn_rad, const std::string& symbologies,
                                    bool try_rotate) {
  const int x0 = std::clamp(window.x, 0, latent.width), y0 = std::clamp(window.y, 0, latent.height);
  const int x1 = std::clamp(window.x + window.width, x0, latent.width);
  const int y1 = std::clamp(window.y + window.height, y0, latent.height);
  if (x1 - x0 < 1 || y1 - y0 < 1) return {};
  const double c = std::cos(turn_rad), s = std::sin(turn_rad);
  const double w = x1 - x0, h = y1 - y0;
  // The turned plane holds the whole window: its bounding box once turned.
  const int tw = static_cast<int>(std::ceil(w * std::abs(c) + h * std::abs(s)));
  const int th = static_cast<int>(std::ceil(w * std::abs(s) + h * std::abs(c)));
  const double cx = x0 + w / 2, cy = y0 + h / 2, tcx = tw / 2.0, tcy = th / 2.0;
  // A pixel's position (its index) in the turned plane -> the latent's: about
  // the centres, (0, 1) in the turned plane along the leaning line.
  auto back = [&](double& x, double& y) {
    const double du = x + 0.5 - tcx, dv = y + 0.5 - tcy;
    x = cx + du * c + dv * s - 0.5;
    y = cy - du * s + dv * c - 0.5;
  };
  double x00 = 0, y00 = 0;
  back(x00, y00);
  const cv::Matx23d to_latent(c, s, x00, -s, c, y00);
  imaging::Plane turned = imaging::Plane::uninitialised(tw, th);
  const cv::Mat from(latent.height, latent.width, CV_32F, const_cast<float*>(latent.pixels.data()));
  cv::Mat to(th, tw, CV_32F, turned.pixels.data());
  cv::warpAffine(from, to, to_latent, to.size(), cv::INTER_LINEAR | cv::WARP_INVERSE_MAP,
                 cv::BORDER_REPLICATE);
  DecodeWindow whole{0, 0, tw, th};
  // A turned row samples two rows of the latent (bilinear): one row more apart.
  whole.independent_apart = window.independent_apart > 0 ? window.independent_apart + 1 : 0;
  BarcodeReadout out = read_barcodes(turned, symbologies, try_rotate, {&whole, 1});
  for (auto* codes : {&out.codes, &out.unconfirmed})
    for (DecodedCode& code : *codes) {
      back(code.centre_x, code.centre_y);
      code.min_x = INFINITY;
      code.max_x = -INFINITY;
      for (CodePoint& corner : code.quality.corners) {
        back(corner.x, corner.y);
        code.min_x = std::min(code.min_x, corner.x);
        code.max_x = std::max(code.max_x, corner.x);
      }
    }
  return out;
}

bool quiet_zones_clear(const DecodedCode& code, const imaging::Plane& latent) {
  const CodeQuality& q = code.quality;
  if (!q.measured || q.module_px <= 0) return true;
  const double dark = q.r_min + (q.r_max - q.r_min) / 4;
  auto lerp = [](const CodePoint& a, const CodePoint& b, double t) {
    return CodePoint{a.x + (b.x - a.x) * t, a.y + (b.y - a.y) * t};
  };
  const CodeCorners& c = q.corners;
  // Each end (0: left, 1: right): from the symbol's edge on each line, away from it along the line.
  for (const int end : {0, 1}) {
    // An EAN/UPC's add-on may follow its right end: less of that side judged.
    const bool add_on_side = end == 1 && is_ean_upc(code.format);
    const int steps = static_cast<int>(
        std::ceil((add_on_side ? kAddOnQuietModules : kQuietModules) * q.module_px));
    std::vector<double> profile(static_cast<std::size_t>(steps), 0.0);
    bool inside = true;
    for (const double t : {0.25, 0.5, 0.75}) {
      const CodePoint left = lerp(c[0], c[3], t), right = lerp(c[1], c[2], t);
      const double dx = right.x - left.x, dy = right.y - left.y, length = std::hypot(dx, dy);
      if (length <= 0) return true;
      const double ux = dx / length, uy = dy / length, away = end == 0 ? -1.0 : 1.0;
      const CodePoint& from = end == 0 ? left : right;
      for (int i = 0; i < steps && inside; ++i) {
        const auto v =
            imaging::bilinear(latent, from.x + away * ux * (i + 1), from.y + away * uy * (i + 1));
        inside = v.has_value();
        profile[static_cast<std::size_t>(i)] += v.value_or(0.0) / 3;
      }
    }
    if (!inside) continue;
    const int module = std::max(1, static_cast<int>(std::lround(q.module_px)));
    // From a module and a half out: the symbol's last edge, blurred, reaches that far.
    for (int i = static_cast<int>(1.5 * q.module_px); i + module <= steps; ++i) {
      double run = 0;
      for (int k = 0; k < module; ++k) run += profile[static_cast<std::size_t>(i + k)];
      if (run / module < dark) return false;
    }
  }
  return true;
}

namespace {

/// Whether linear codes `a` and `b` lie over one place: their corners' boxes,
/// widened by 4 px, meet, and along the reading direction share half the
/// shorter one's length (ZXing reports the lines it read a symbol on: one
/// symbol read on two bands of its bars, 162-226 and 218-274 of a real EAN-13).
bool over_one_place(const DecodedCode& a, const DecodedCode& b) {
  auto box = [](const DecodedCode& c) {
    std::array<double, 4> r{c.quality.corners[0].x, c.quality.corners[0].y, c.quality.corners[0].x,
                            c.quality.corners[0].y};
    for (const CodePoint& p : c.quality.corners)
      r = {std::min(r[0], p.x), std::min(r[1], p.y), std::max(r[2], p.x), std::max(r[3], p.y)};
    return r;
  };
  const auto ra = box(a), rb = box(b);
  constexpr double kWiden = 4;
  const double across_x = std::min(ra[2], rb[2]) - std::max(ra[0], rb[0]) + 2 * kWiden;
  const double across_y = std::min(ra[3], rb[3]) - std::max(ra[1], rb[1]) + 2 * kWiden;
  if (across_x <= 0 || across_y <= 0) return false;
  const double turn = a.orientation_deg * std::numbers::pi / 180;
  const bool along_x = std::abs(std::cos(turn)) >= std::abs(std::sin(turn));
  const double shorter =
      along_x ? std::min(ra[2] - ra[0], rb[2] - rb[0]) : std::min(ra[3] - ra[1], rb[3] - rb[1]);
  return (along_x ? across_x : across_y) >= shorter / 2;
}

}  // namespace

void drop_conflicting(std::vector<DecodedCode>& codes) {
  std::vector<bool> drop(codes.size(), false);
  for (std::size_t i = 0; i < codes.size(); ++i)
    for (std::size_t j = i + 1; j < codes.size(); ++j) {
      const DecodedCode &a = codes[i], &b = codes[j];
      if (symbology_family(a.format) != symbology_family(b.format) || a.text == b.text ||
          !is_linear_format(a.format))
        continue;
      if (over_one_place(a, b)) drop[i] = drop[j] = true;
    }
  std::vector<DecodedCode> kept;
  for (std::size_t i = 0; i < codes.size(); ++i)
    if (!drop[i]) kept.push_back(std::move(codes[i]));
  codes = std::move(kept);
}

std::vector<std::string> code_texts(const BarcodeReadout& readout) {
  std::vector<std::string> texts;
  for (const DecodedCode& code : readout.codes) texts.push_back(code.text);
  return texts;
}

std::vector<LabelRegion> find_paper_runs(const imaging::Plane& latent, double paper_threshold,
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
  for (LabelRegion& r : runs) {
    const int row_need = std::max(1, static_cast<int>(min_fraction * (r.end - r.begin)));
    for (int y = 0; y < latent.height; ++y) {
      const float* row = latent.row(y).data();
      int paper = 0;
      for (int x = r.begin; x < r.end; ++x) paper += row[x] > paper_threshold ? 1 : 0;
      if (paper < row_need) continue;
      if (r.across_end == 0) r.across_begin = y;
      r.across_end = y + 1;
    }
  }
  // A linear code's bars and narrow spaces can make a gap wider than max_gap
  // (in dim light the spaces fall below the threshold in the noise): the label
  // falls into runs none of which holds the whole symbol. The paper above and
  // below the bars is still there: neighbouring runs are one label when every
  // column between them has paper in at least min_fraction of the rows the two
  // span (a belt between two labels has next to none).
  auto paper_through = [&](int x0, int x1, int top, int bottom) {
    const int gap_need = std::max(2, static_cast<int>(min_fraction * (bottom - top)));
    for (int x = x0; x < x1; ++x) {
      int paper = 0;
      for (int y = top; y < bottom && paper < gap_need; ++y)
        paper += latent.at(x, y) > paper_threshold;
      if (paper < gap_need) return false;
    }
    return true;
  };
  auto bars_between = [&](const LabelRegion& a, const LabelRegion& b) {
    if (!a.rows_measured() || !b.rows_measured() || a.across_begin >= b.across_end ||
        b.across_begin >= a.across_end)
      return false;
    return paper_through(a.end, b.begin, std::min(a.across_begin, b.across_begin),
                         std::max(a.across_end, b.across_end));
  };
  // Cut: a run that touches the frame's edge, or ends short of it and may still
  // go on past it: through a dark gap no wider than max_gap (bars at the edge),
  // or through bars with paper above and below them to the edge.
  auto reaches_edge = [&](const LabelRegion& r) {
    if (r.begin <= max_gap || latent.width - r.end <= max_gap) return true;
    return r.rows_measured() && (paper_through(0, r.begin, r.across_begin, r.across_end) ||
                                 paper_through(r.end, latent.width, r.across_begin, r.across_end));
  };
  for (LabelRegion& r : runs) r.cut = reaches_edge(r);
  std::vector<LabelRegion> joined;
  for (const LabelRegion& run : runs) {
    if (joined.empty() || !bars_between(joined.back(), run)) {
      joined.push_back(run);
      continue;
    }
    LabelRegion& last = joined.back();
    last.end = run.end;
    last.cut = last.cut || run.cut;
    last.across_begin = std::min(last.across_begin, run.across_begin);
    last.across_end = std::max(last.across_end, run.across_end);
  }
  for (const LabelRegion& r : joined)
    if (r.end - r.begin >= min_width || r.cut) regions.push_back(r);
  return regions;
}

std::string decode_area_name(DecodeArea area) {
  return area == DecodeArea::kFrame ? "frame" : "labels";
}

std::optional<DecodeArea> decode_area_from_name(const std::string& name) {
  for (DecodeArea area : {DecodeArea::kFrame, DecodeArea::kLabels})
    if (decode_area_name(area) == name) return area;
  return std::nullopt;
}

std::vector<DecodeWindow> decode_windows(std::span<const LabelRegion> runs, int width, int height,
                                         imaging::Direction direction, int margin) {
  const bool along_x = imaging::moves_along_x(direction);
  const int length = imaging::length_along_motion(direction, width, height);
  // The camera coordinate of the boundary before motion-frame sample `n`
  // (mirrored for -x and -y: the boundary before n is then after its pixel).
  auto camera_boundary = [&](int n) {
    return static_cast<int>(std::lround(
        imaging::position_along_motion(direction, n - 0.5, n - 0.5, width, height) + 0.5));
  };
  std::vector<DecodeWindow> windows;
  for (const LabelRegion& r : runs) {
    const int a = camera_boundary(std::max(0, r.begin - margin));
    const int b = camera_boundary(std::min(length, r.end + margin));
    const int begin = std::min(a, b), end = std::max(a, b);
    const int lines = along_x ? height : width;
    const bool measured = r.rows_measured();
    const int top = measured ? std::max(0, r.across_begin - margin) : 0;
    const int bottom = measured ? std::min(lines, r.across_end + margin) : lines;
    windows.push_back(along_x ? DecodeWindow{begin, top, end - begin, bottom - top}
                              : DecodeWindow{top, begin, bottom - top, end - begin});
  }
  return windows;
}

void measure_and_place(DecodedCode& code, const imaging::Plane& latent,
                       const CodeCorners& corners) {
  code.quality = measure_code(latent, code.format, corners);
  double sx = 0, sy = 0;
  code.min_x = code.max_x = code.quality.corners[0].x;
  for (const CodePoint& c : code.quality.corners) {
    sx += c.x;
    sy += c.y;
    code.min_x = std::min(code.min_x, c.x);
    code.max_x = std::max(code.max_x, c.x);
  }
  code.centre_x = sx / 4;
  code.centre_y = sy / 4;
}

}  // namespace flutterscan::reader
