#include "session/window_tries.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

#include "imaging/deblur.hpp"
#include "imaging/total_variation.hpp"
#include "reader/bar_pattern_fit.hpp"
#include "reader/code_measure.hpp"

namespace flutterscan::session {
namespace {

/// Rows summed either side of each along a linear code's bars, in turn while
/// nothing reads: 17 in all (a quarter of the noise's rms), then 49 (a seventh:
/// the bars of most labels are taller; docs/algorithms.md, "Sums along the bars").
constexpr std::array<int, 2> kBarHalfRows = {8, 24};
/// Rows either side the bars' slope is judged over, at the least: more than
/// 17 rows summed, so that a slope off by a little loses contrast enough to
/// tell; the taller sums' slope is judged over as many rows as they sum (a
/// slope's error shifts the outer rows the further).
constexpr int kSlopeHalfRows = 16;

/// tv's kappa on the bar sums where joint Wiener's read nothing: half the
/// reading weight (kappa 0.15 read ean13-2-04 and -05 of the real-print photos
/// on the 17-row sums where the reading weight flattened their narrow spaces).
constexpr double kBarSumsTvWeight = 0.15;
/// How much better, in noise variances, each character of a value tv's sums
/// read must fit joint Wiener's sums than any other character allowed in its
/// place (reader::fit_bar_pattern): tv's flat steps on a noisy profile can
/// read another value that passes the check digit, which joint Wiener's sums
/// (no prior: only the light's evidence) do not support.
constexpr double kMinFitMargin = 1.0;

/// What reading an EAN-13 by fit on a row of a window's bar sums is expected
/// to cost: ms, and ms per sample of the row (reader::read_ean13_by_fit;
/// deblur_bench ReadEan13ByFit, AMD EPYC: 30, 40 and 58 ms on rows of 320,
/// 640 and 1280 samples, about 26 ms and 0.025 ms a sample; half as much again
/// for headroom).
constexpr double kFitMs = 40, kFitMsPerSample = 0.04;

/// A bar slope from which a window is also read turned upright: 0.05 px per
/// row, 3 degrees (a 40 px tall code 300 px long then drifts 15 px across the rows).
constexpr double kMinTurnSlope = 0.05;

/// The lean from the vertical, in the camera's orientation, of bars whose
/// slope in the motion frame is `slope` (px along the motion per line; the
/// convention of reader::read_barcodes_turned: positive, lower end toward larger x).
double camera_lean(imaging::Direction direction, double slope) {
  switch (direction) {
    case imaging::Direction::kPlusX:
      return std::atan(slope);
    case imaging::Direction::kMinusX:
      return -std::atan(slope);
    case imaging::Direction::kPlusY:  // lines are columns: the bars lie near the rows
      return std::atan2(1.0, slope);
    case imaging::Direction::kMinusY:
      return std::atan2(-1.0, slope);
  }
  return std::atan(slope);
}

/// An EAN-13 on a window's bar sums read by fit (reader::read_ean13_by_fit),
/// over the whole row (the bars' box, judged in 64 px tiles, cut ean13-2-05 of
/// the real-print photos 40 px short of its end), on two rows of the longest
/// run of rows across the bars that sum no row in common (2 `half_rows` + 1
/// apart): two independent readings, which must agree (a fit has no decoder
/// to back it otherwise). `row` and the run's rows say where.
struct FitOnSums {
  reader::FittedRead read;
  int row = 0;
  int first_row = 0, last_row = 0;
};

FitOnSums read_sums_by_fit(const imaging::Plane& sums, const std::vector<bool>& across,
                           int half_rows) {
  FitOnSums out;
  int best = 0;
  for (int y = 0; y < sums.height;) {
    if (!across[static_cast<std::size_t>(y)]) {
      ++y;
      continue;
    }
    int end = y;
    while (end < sums.height && across[static_cast<std::size_t>(end)]) ++end;
    if (end - y > best) {
      best = end - y;
      out.first_row = y;
      out.last_row = end - 1;
    }
    y = end;
  }
  const int apart = 2 * half_rows + 1;
  if (best < apart + 1) {
    out.read.problem = best == 0 ? "no row crosses the bars"
                                 : "too few rows across the bars for two independent fits";
    return out;
  }
  out.row = (out.first_row + out.last_row + 1 - apart) / 2;
  auto fitted = [&](int row) {
    std::vector<double> samples;
    for (int x = 0; x < sums.width; ++x) samples.push_back(sums.at(x, row));
    return reader::read_ean13_by_fit(samples, 0, sums.width);
  };
  out.read = fitted(out.row);
  if (out.read.text.empty()) return out;
  const reader::FittedRead other = fitted(out.row + apart);
  if (other.text != out.read.text) {
    out.read.problem = "the independent row " + std::to_string(apart) + " rows on read " +
                       (other.text.empty() ? "nothing (" + other.problem + ")" : other.text);
    out.read.text.clear();
  }
  return out;
}

/// The code `fit` read on sums of 2 `half_rows` + 1 rows along `slope`, its
/// corners (quality.corners, unmeasured) in the crop's coordinates: the bars' ends along the row
/// read, over the rows its run of sums covers (`height` the crop's), following the bars' slope, in
/// the symbol's reading order (read right to left, it is upside down). An EAN-13 that starts with 0
/// is a UPC-A where `upc_a` is read, as ZXing reports it.
reader::DecodedCode fitted_code(const FitOnSums& fit, const imaging::BarSlope& slope, int half_rows,
                                int height, bool upc_a) {
  const double top = std::max(0, fit.first_row - half_rows);
  const double bottom = std::min(height - 1, fit.last_row + half_rows);
  const double at_row = slope.at(fit.read.begin, fit.row);
  auto corner = [&](double x, double y) {
    return reader::CodePoint{x + at_row * (y - fit.row), y};
  };
  const bool upright = fit.read.end > fit.read.begin;
  const double y_top = upright ? top : bottom, y_bottom = upright ? bottom : top;
  reader::DecodedCode code;
  code.quality.corners = {corner(fit.read.begin, y_top), corner(fit.read.end, y_top),
                          corner(fit.read.end, y_bottom), corner(fit.read.begin, y_bottom)};
  code.text = fit.read.text;
  code.format = "EAN-13";
  if (code.text.front() == '0' && upc_a) {
    code.format = "UPC-A";
    code.text.erase(0, 1);
  }
  code.symbology_id = "]E0";
  code.decoder = "fit";
  code.evidence = "halves";
  return code;
}

/// The window's rows, `crop` its samples, summed `half_rows` either side of each
/// along the bars' `slope` and deblurred under the sums' model by `options`.
Result<imaging::DeblurResult, std::string> deblur_bar_sums(const imaging::MotionFrame& crop,
                                                           const imaging::BarSlope& slope,
                                                           int half_rows,
                                                           const imaging::CaptureModel& model,
                                                           const imaging::DeblurOptions& options) {
  auto sums = imaging::MotionFrame::make(imaging::sum_along_bars(crop.image(), slope, half_rows),
                                         imaging::Direction::kPlusX);
  if (!sums.ok()) return Result<imaging::DeblurResult, std::string>::failure(sums.error());
  return imaging::deblur(sums.value(), imaging::model_of_row_sums(model, 2 * half_rows + 1),
                         options);
}

/// `tv` (a window's tv latent) with the rows of `sums` (its bar sums' latent)
/// where `across` says all their rows cross the bars.
imaging::Plane over_rows_across(const imaging::Plane& tv, const imaging::Plane& sums,
                                const std::vector<bool>& across) {
  imaging::Plane composite = tv;
  for (int y = 0; y < composite.height; ++y)
    if (across[static_cast<std::size_t>(y)])
      std::copy_n(sums.row(y).begin(), composite.width, composite.row(y).begin());
  return composite;
}

/// tv's options for a window: the reading weight, one thread.
imaging::DeblurOptions tv_options() {
  imaging::DeblurOptions tv;
  tv.method = imaging::Method::kTotalVariation;
  tv.threads = 1;
  tv.tv_weight_per_noise = imaging::kReadingWeightPerNoise;
  return tv;
}

}  // namespace

std::vector<reader::DecodedCode> supported_reads(const imaging::Plane& sums,
                                                 std::vector<reader::DecodedCode> found,
                                                 std::vector<BarSumsTry::Checked>& checked) {
  std::erase_if(found, [&](const reader::DecodedCode& code) {
    const reader::BarPatternFit fit = reader::fit_bar_pattern(sums, code);
    checked.push_back({code.text, code.format, fit.judged ? fit.worst_margin : 0, fit.problem,
                       fit.judged && fit.worst_margin >= kMinFitMargin});
    return !checked.back().kept;
  });
  return found;
}

std::optional<imaging::Plane> tv_try(SecondPassWindow& window) {
  auto deblurred = imaging::deblur(window.crop(), window.model(), tv_options());
  if (!deblurred.ok()) return std::nullopt;
  imaging::Plane tv = std::move(deblurred.value().latent);
  window.paste(tv);
  window.read_and_take("tv", kRowsTied, window.options().symbologies);
  return tv;
}

std::vector<BarSums> bar_sums_try(SecondPassWindow& window, const imaging::Plane& tv,
                                  const std::string& linear, BarSumsTry& record) {
  // Judged on the first pass's latent (joint Wiener's) of the window kept,
  // not tv's: on a real label turned 8 degrees (ean13-2-05 of the real-print
  // photos, beside a second code, print and shadow) the slope found on tv's
  // latent of the window was 0, on joint Wiener's -0.14, as on the sharp scene
  // (docs/algorithms.md, "Sums along the bars").
  const imaging::Plane& first = window.first();
  const imaging::Plane kept = first.part(window.keep_begin(), 0, window.keep_end(), first.height);
  const imaging::Region bars_box = imaging::bar_region(kept);
  imaging::DeblurOptions wiener;
  wiener.threads = 1;
  std::vector<BarSums> made;
  for (const int half_rows : kBarHalfRows) {
    BarSums sums;
    sums.half_rows = half_rows;
    sums.slope = imaging::bar_slope(kept, bars_box, std::max(kSlopeHalfRows, half_rows));
    record.slope = sums.slope.at(kept.width / 2.0, kept.height / 2.0);
    record.slope_change = sums.slope.per_column * kept.width;
    // Bars that lean: a short code's rows may not cross it whole; read turned upright too.
    sums.turn_rad =
        std::abs(record.slope) >= kMinTurnSlope ? camera_lean(window.direction(), record.slope) : 0;
    sums.across = imaging::rows_across_bars(kept, sums.slope, half_rows);
    sums.slope.origin_x += window.keep_begin();  // from the kept columns' coordinates to the crop's
    auto profile = deblur_bar_sums(window.crop(), sums.slope, half_rows, window.model(), wiener);
    if (!profile.ok()) break;
    record.rows.push_back(2 * half_rows + 1);
    sums.wiener = std::move(profile.value().latent);
    sums.composite = over_rows_across(tv, sums.wiener, sums.across);
    window.paste(sums.composite);
    // Joint Wiener deblurs each row of the sums on its own; sums 2h + 1 rows
    // apart share no row of the frame.
    const int apart = 2 * half_rows + 1;
    std::vector<reader::DecodedCode> found = window.read(apart, linear);
    if (found.empty() && sums.turn_rad != 0) found = window.read(apart, linear, sums.turn_rad);
    // The frame shows tv's latent, and the sums' over the rows of the codes
    // they read only: the sums smear whatever else the window holds (a
    // matrix code above or below that tv or the first pass read, text)
    // along the bars' slope.
    window.paste(tv);
    if (!found.empty()) window.paste(sums.composite, found);
    record.read = window.take(std::move(found), "bar-sums");
    made.push_back(std::move(sums));
    if (!record.read.empty()) break;
  }
  return made;
}

std::vector<std::string> tv_on_sums_try(SecondPassWindow& window, const BarSums& sums,
                                        const imaging::Plane& tv, const std::string& linear,
                                        BarSumsTry& record) {
  // Noise that joint Wiener's leaves hides narrow spaces: tv on the same sums,
  // each value it reads checked against joint Wiener's sums.
  imaging::DeblurOptions tv_sums = tv_options();
  tv_sums.tv_weight_per_noise = kBarSumsTvWeight;
  record.tv_rows.push_back(2 * sums.half_rows + 1);
  auto profile =
      deblur_bar_sums(window.crop(), sums.slope, sums.half_rows, window.model(), tv_sums);
  if (!profile.ok()) return {};
  const imaging::Plane composite = over_rows_across(tv, profile.value().latent, sums.across);
  window.paste(composite);
  std::vector<reader::DecodedCode> found = window.read(kRowsTied, linear);
  if (found.empty() && sums.turn_rad != 0) found = window.read(kRowsTied, linear, sums.turn_rad);
  window.paste(sums.composite);
  found = supported_reads(window.camera(), std::move(found), record.tv_checked);
  window.paste(tv);
  if (!found.empty()) window.paste(composite, found);
  record.read = window.take(std::move(found), "tv-on-sums");
  return record.read;
}

double fit_estimate_ms(const SecondPassWindow& window) {
  return 2 * (kFitMs + kFitMsPerSample * window.crop().along());  // two rows
}

std::vector<std::string> fit_try(SecondPassWindow& window, const BarSums& sums,
                                 const imaging::Plane& tv, bool upc_a, BarSumsTry& record) {
  const FitOnSums fit = read_sums_by_fit(sums.wiener, sums.across, sums.half_rows);
  BarSumsTry::Checked verdict{fit.read.text, "EAN-13", fit.read.worst_margin, fit.read.problem,
                              !fit.read.text.empty()};
  std::vector<std::string> read;
  if (verdict.kept) {
    reader::DecodedCode code =
        fitted_code(fit, sums.slope, sums.half_rows, sums.wiener.height, upc_a);
    verdict.text = code.text;
    verdict.format = code.format;
    // Measured on the sums it was read on, in the camera's coordinates.
    reader::CodeCorners corners = code.quality.corners;
    for (reader::CodePoint& p : corners) {
      const auto [cx, cy] =
          imaging::camera_point<double>(window.direction(), p.x + window.crop_begin(),
                                        p.y + window.first_line(), window.frame_along());
      p = {cx, cy};
    }
    window.paste(sums.composite);
    reader::measure_and_place(code, window.camera(), corners);
    window.paste(tv);
    if (!window.holds(code)) {
      const std::vector<reader::DecodedCode> one = {code};
      window.paste(sums.composite, one);
      read = window.take(one, "fit");
      record.read = read;
    }
  }
  record.fitted.push_back(std::move(verdict));
  return read;
}

std::vector<std::string> isotropic_tv_try(SecondPassWindow& window, double weight,
                                          const imaging::Plane& tv, IsotropicTry& record) {
  // tv's prior has the print constant across the motion (bars upright), which
  // a matrix code's modules and a turned label's bars are not.
  imaging::DeblurOptions isotropic = tv_options();
  isotropic.tv_across_ratio = 1;
  isotropic.tv_weight_per_noise = weight;
  record.weights.push_back(weight);
  auto deblurred = imaging::deblur(window.crop(), window.model(), isotropic);
  if (!deblurred.ok()) return {};
  window.paste(deblurred.value().latent);
  record.read = window.read_and_take("isotropic-tv", kRowsTied, window.options().symbologies);
  if (record.read.empty()) window.paste(tv);
  return record.read;
}

}  // namespace flutterscan::session
