#include "session/second_pass.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <utility>

#include "imaging/bar_sums.hpp"
#include "imaging/deblur.hpp"
#include "imaging/total_variation.hpp"
#include "reader/bar_pattern_fit.hpp"
#include "reader/code_reading.hpp"
#include "reader/code_regions.hpp"
#include "session/session_config.hpp"

namespace flutterscan::session {
namespace {

/// Along and across the motion, what a window keeps around its paper: the
/// decode window's margin (decode_windows' default).
constexpr int kWindowMargin = 24;
/// Beyond the blur, what the crop adds at each end along the motion: the
/// latent within one blur of a crop's ends is not determined by the crop's
/// samples (docs/algorithms.md, borders), and the periodic extension rings a
/// little further.
constexpr int kCropSlack = 16;
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

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
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

bool inside(const reader::DecodeWindow& w, double x, double y) {
  return x >= w.x && x < w.x + w.width && y >= w.y && y < w.y + w.height;
}

/// Whether camera point (x, y) lies in the rows of linear code `code` (its
/// corners' rows, widened by 4 px), whatever its column: the rows ZXing reads
/// it on, with their quiet zones and the paper beside them.
bool on_code_rows(const reader::DecodedCode& code, double y) {
  const auto [y0, y1] = reader::corner_rows(code);
  return y >= y0 - 4 && y <= y1 + 4;
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

}  // namespace

BeltBox belt_box(const reader::DecodedCode& code, imaging::Direction direction, int width,
                 int height, double travel_px) {
  const bool along_x = imaging::moves_along_x(direction);
  auto along = [&](const reader::CodePoint& p) {
    return imaging::position_along_motion(direction, p.x, p.y, width, height) - travel_px;
  };
  auto across = [&](const reader::CodePoint& p) { return along_x ? p.y : p.x; };
  const reader::CodePoint& c0 = code.quality.corners[0];
  BeltBox box{along(c0), along(c0), across(c0), across(c0)};
  for (const reader::CodePoint& p : code.quality.corners) {
    box.begin = std::min(box.begin, along(p));
    box.end = std::max(box.end, along(p));
    box.across_begin = std::min(box.across_begin, across(p));
    box.across_end = std::max(box.across_end, across(p));
  }
  return box;
}

void BeltReads::add(const BeltBox& code) {
  const std::lock_guard lock(mutex_);
  if (reads_.size() < kKept)
    reads_.push_back(code);
  else
    reads_[next_] = code;
  next_ = (next_ + 1) % kKept;
}

bool BeltReads::any_over(const BeltBox& region) const {
  const std::lock_guard lock(mutex_);
  const bool lines_given = region.across_end > region.across_begin;
  return std::any_of(reads_.begin(), reads_.end(), [&](const BeltBox& code) {
    return code.begin <= region.end && code.end >= region.begin &&
           (!lines_given ||
            (code.across_begin <= region.across_end && code.across_end >= region.across_begin));
  });
}

SecondPassBudget::SecondPassBudget(double per_frame_ms, int workers)
    : per_frame_ms_(per_frame_ms), workers_(std::max(1, workers)) {}

void SecondPassBudget::add_frame(std::uint64_t index, std::int64_t camera_ns,
                                 double first_pass_ms) {
  const std::lock_guard lock(mutex_);
  if (seen_frame_ && index > last_index_ && camera_ns > last_camera_ns_) {
    const double period = static_cast<double>(camera_ns - last_camera_ns_) * 1e-6 /
                          static_cast<double>(index - last_index_);
    if (period < 1000) period_ms_ = period_ms_ == 0 ? period : 0.9 * period_ms_ + 0.1 * period;
  }
  if (!seen_frame_ || index > last_index_) {
    last_index_ = index;
    last_camera_ns_ = camera_ns;
    seen_frame_ = true;
  }
  double added = 0, bound = 0;
  if (per_frame_ms_ >= 0) {
    added = per_frame_ms_;
    bound = 2 * per_frame_ms_;
  } else if (period_ms_ > 0) {
    const double available = period_ms_ * workers_ * kShare;  // per frame, all workers
    added = available - first_pass_ms;
    bound = 2 * available;
  }
  credit_ms_ = std::clamp(credit_ms_ + added, -bound, bound);
}

bool SecondPassBudget::take(double estimate_ms) {
  const std::lock_guard lock(mutex_);
  if (credit_ms_ < estimate_ms) return false;
  credit_ms_ -= estimate_ms;
  return true;
}

void SecondPassBudget::settle(double estimate_ms, double actual_ms, std::size_t pixels) {
  const std::lock_guard lock(mutex_);
  credit_ms_ -= actual_ms - estimate_ms;
  if (pixels > 0 && actual_ms > 0)
    ms_per_megapixel_ =
        0.8 * ms_per_megapixel_ + 0.2 * actual_ms / (static_cast<double>(pixels) * 1e-6);
}

double SecondPassBudget::estimate_ms(std::size_t pixels) const {
  const std::lock_guard lock(mutex_);
  return ms_per_megapixel_ * static_cast<double>(pixels) * 1e-6;
}

double SecondPassBudget::credit_ms() const {
  const std::lock_guard lock(mutex_);
  return credit_ms_;
}

nlohmann::json SecondPass::log(double credit_ms) const {
  nlohmann::json windows = nlohmann::json::array();
  for (const WindowRetry& r : retried) {
    nlohmann::json window = {{"x", r.window.x},
                             {"y", r.window.y},
                             {"width", r.window.width},
                             {"height", r.window.height},
                             {"ms", std::round(r.ms * 100) / 100},
                             {"read", r.read}};
    if (r.bar_sums)
      window["bar_sums"] = {{"slope", std::round(r.bar_sums->slope * 100) / 100},
                            {"slope_change", std::round(r.bar_sums->slope_change * 100) / 100},
                            {"rows", r.bar_sums->rows},
                            {"read", r.bar_sums->read}};
    if (r.bar_sums && !r.bar_sums->tv_rows.empty()) {
      nlohmann::json checked = nlohmann::json::array();
      for (const BarSumsTry::Checked& c : r.bar_sums->tv_checked) {
        nlohmann::json one = {{"text", c.text}, {"format", c.format}, {"kept", c.kept}};
        if (c.problem.empty())
          one["margin"] = std::round(c.margin * 10) / 10;
        else
          one["problem"] = c.problem;
        checked.push_back(std::move(one));
      }
      window["bar_sums"]["tv"] = {{"rows", r.bar_sums->tv_rows}, {"checked", std::move(checked)}};
    }
    if (r.bar_sums && !r.bar_sums->fitted.empty()) {
      nlohmann::json fitted = nlohmann::json::array();
      for (const BarSumsTry::Checked& c : r.bar_sums->fitted) {
        nlohmann::json one = {{"kept", c.kept}};
        if (c.kept) {
          one["text"] = c.text;
          one["format"] = c.format;
          one["margin"] = std::round(c.margin * 10) / 10;
        } else {
          one["problem"] = c.problem;
        }
        fitted.push_back(std::move(one));
      }
      window["bar_sums"]["fitted"] = std::move(fitted);
    }
    if (r.isotropic)
      window["isotropic"] = {{"read", r.isotropic->read}, {"weights", r.isotropic->weights}};
    windows.push_back(std::move(window));
  }
  return {{"windows", std::move(windows)},
          {"skipped", skipped},
          {"read_before", read_before},
          {"credit_ms", std::round(credit_ms * 10) / 10}};
}

std::vector<reader::LabelRegion> unread_runs(std::span<const reader::LabelRegion> paper,
                                             const reader::BarcodeReadout& readout,
                                             imaging::Direction direction, int width, int height) {
  const std::vector<reader::DecodeWindow> windows =
      reader::decode_windows(paper, width, height, direction, kWindowMargin);
  std::vector<reader::LabelRegion> unread;
  for (std::size_t i = 0; i < paper.size(); ++i) {
    const bool read = std::any_of(readout.codes.begin(), readout.codes.end(), [&](const auto& c) {
      return inside(windows[i], c.centre_x, c.centre_y);
    });
    if (!read) unread.push_back(paper[i]);
  }
  return unread;
}

std::vector<reader::LabelRegion> retry_regions(std::span<const reader::LabelRegion> unread_paper,
                                               std::span<const reader::LabelRegion> unread_code) {
  std::vector<reader::LabelRegion> out(unread_paper.begin(), unread_paper.end());
  for (const reader::LabelRegion& c : unread_code) {
    const bool on_paper = std::any_of(unread_paper.begin(), unread_paper.end(),
                                      [&](const reader::LabelRegion& p) { return p.overlaps(c); });
    if (!on_paper) out.push_back(c);
  }
  return out;
}

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

SecondPass run_second_pass(const SecondPassFrame& frame,
                           std::span<const reader::LabelRegion> unread,
                           const reader::ReaderOptions& options, const SecondPassTries& tries,
                           SecondPassBudget& budget, BeltReads& reads,
                           reader::BarcodeReadout& readout) {
  SecondPass out;
  const imaging::MotionFrame& electrons = frame.electrons;
  const int along = electrons.along(), lines = electrons.lines();
  const imaging::Direction direction = electrons.direction();
  const bool along_x = imaging::moves_along_x(direction);
  const int camera_width = along_x ? along : lines, camera_height = along_x ? lines : along;
  const int blur = static_cast<int>(std::ceil(frame.model.blur_px)) + 1;
  imaging::DeblurOptions tv;
  tv.method = imaging::Method::kTotalVariation;
  tv.threads = 1;
  tv.tv_weight_per_noise = imaging::kReadingWeightPerNoise;
  imaging::DeblurOptions tv_isotropic = tv;
  tv_isotropic.tv_across_ratio = 1;
  imaging::DeblurOptions wiener_sums;
  wiener_sums.threads = 1;
  imaging::DeblurOptions tv_sums = tv;
  tv_sums.tv_weight_per_noise = kBarSumsTvWeight;
  const std::string linear = reader::linear_symbologies(options.symbologies);
  const bool reads_ean13 = reader::names_symbology(options.symbologies, "EAN-13"),
             reads_upc_a = reader::names_symbology(options.symbologies, "UPC-A");
  const imaging::Plane& camera =
      frame.camera_latent != nullptr ? *frame.camera_latent : frame.motion_latent;
  for (const reader::LabelRegion& run : unread) {
    if (reads.any_over({run.begin - frame.travel_px, run.end - frame.travel_px,
                        static_cast<double>(run.across_begin),
                        static_cast<double>(run.across_end)})) {
      ++out.read_before;
      continue;
    }
    // The window kept, and the crop deblurred around it (motion frame).
    const int keep0 = std::max(0, run.begin - kWindowMargin);
    const int keep1 = std::min(along, run.end + kWindowMargin);
    const int c0 = std::max(0, keep0 - blur - kCropSlack);
    const int c1 = std::min(along, keep1 + blur + kCropSlack);
    const bool rows_known = run.rows_measured();
    const int r0 = rows_known ? std::max(0, run.across_begin - kWindowMargin) : 0;
    const int r1 = rows_known ? std::min(lines, run.across_end + kWindowMargin) : lines;
    if (c1 - c0 <= blur || r1 <= r0) continue;
    const auto pixels = static_cast<std::size_t>(c1 - c0) * static_cast<std::size_t>(r1 - r0);
    const double estimate = budget.estimate_ms(pixels);
    if (!budget.take(estimate)) {
      ++out.skipped;
      continue;
    }
    const auto t0 = std::chrono::steady_clock::now();
    double own_ms = 0;  // the tries settled on their own (tv on the bar sums, isotropic tv)
    imaging::Image crop;
    for (int c = 0; c < electrons.channel_count(); ++c)
      crop.channels.push_back(electrons.channel(c).part(c0, r0, c1, r1));
    WindowRetry retry;
    retry.window =
        reader::decode_windows({&run, 1}, camera_width, camera_height, direction, kWindowMargin)[0];
    // Writes `patch` (the crop's latent) into the latents over the window kept
    // or, given `codes`, over their rows only (on_code_rows()).
    auto paste = [&](const imaging::Plane& patch, std::span<const reader::DecodedCode> codes = {}) {
      for (int y = r0; y < r1; ++y)
        for (int n = keep0; n < keep1; ++n) {
          const auto [x, cy] = imaging::camera_point(direction, n, y, along);
          if (!codes.empty() && std::none_of(codes.begin(), codes.end(),
                                             [&](const auto& c) { return on_code_rows(c, cy); }))
            continue;
          const float v = patch.at(n - c0, y - r0);
          frame.motion_latent.at(n, y) = v;
          if (frame.camera_latent != nullptr) frame.camera_latent->at(x, cy) = v;
        }
    };
    // The codes read in this window before it was deblurred again (the first
    // pass's, offline): the latent pasted must read them too, or it is not kept.
    std::vector<reader::DecodedCode> held;
    for (const reader::DecodedCode& c : readout.codes)
      if (inside(retry.window, c.centre_x, c.centre_y)) held.push_back(c);
    bool held_read = held.empty();  // all of them read again by the last read_again()
    // Reads the window on the latents as pasted, made by try `pass`: the codes
    // not in the readout. Joint Wiener's sums deblur each row on its own; tv's
    // prior ties rows together (reader::DecodeWindow::independent_rows).
    auto read_window = [&](const char* pass, const std::string& symbologies, double turn_rad = 0) {
      reader::DecodeWindow window = retry.window;
      window.independent_rows = std::string(pass) == "bar-sums";
      reader::BarcodeReadout again =
          turn_rad == 0
              ? reader::read_barcodes(camera, symbologies, options.try_rotate, {&window, 1})
              : reader::read_barcodes_turned(camera, window, turn_rad, symbologies,
                                             options.try_rotate);
      for (reader::DecodedCode& code : again.unconfirmed)
        if (std::none_of(readout.unconfirmed.begin(), readout.unconfirmed.end(),
                         [&](const auto& c) { return reader::same_symbol(c, code); }))
          readout.unconfirmed.push_back(std::move(code));
      held_read = std::all_of(held.begin(), held.end(), [&](const reader::DecodedCode& h) {
        return std::any_of(again.codes.begin(), again.codes.end(),
                           [&](const reader::DecodedCode& c) { return reader::same_symbol(c, h); });
      });
      std::erase_if(again.codes, [&](const reader::DecodedCode& code) {
        return std::any_of(
            readout.codes.begin(), readout.codes.end(),
            [&](const reader::DecodedCode& c) { return reader::same_symbol(c, code); });
      });
      return std::move(again.codes);
    };
    // `codes`, read on the latent try `pass` made, join the readout. Returns their values.
    auto take = [&](std::vector<reader::DecodedCode> codes, const char* pass) {
      std::vector<std::string> texts;
      for (reader::DecodedCode& code : codes) {
        code.pass = pass;
        texts.push_back(code.text);
        reads.add(belt_box(code, direction, camera_width, camera_height, frame.travel_px));
        readout.codes.push_back(std::move(code));
      }
      retry.read.insert(retry.read.end(), texts.begin(), texts.end());
      return texts;
    };
    auto read_again = [&](const char* pass, const std::string& symbologies, double turn_rad = 0) {
      return take(read_window(pass, symbologies, turn_rad), pass);
    };
    // The crop is in the motion frame already (+x); its samples passed the frame's checks.
    const auto cropped = imaging::MotionFrame::make(std::move(crop), imaging::Direction::kPlusX);
    using DeblurOut = Result<imaging::DeblurResult, std::string>;
    const DeblurOut deblurred = cropped.ok() ? imaging::deblur(cropped.value(), frame.model, tv)
                                             : DeblurOut::failure(cropped.error());
    if (deblurred.ok()) {
      // The first pass's latent over the window kept, in the crop's coordinates
      // (paste()'s): put back if tv's loses a code the window read before, and
      // where the bars' slope is measured.
      imaging::Plane first = imaging::Plane::uninitialised(c1 - c0, r1 - r0);
      for (int y = r0; y < r1; ++y)
        for (int n = keep0; n < keep1; ++n) first.at(n - c0, y - r0) = frame.motion_latent.at(n, y);
      const imaging::Plane& patch = deblurred.value().latent;
      paste(patch);
      const std::size_t before = readout.codes.size();
      read_again("tv", options.symbologies);
      auto linear_format = [](const reader::DecodedCode& c) {
        return reader::is_linear_format(c.format);
      };
      const bool linear_read =
          std::any_of(held.begin(), held.end(), linear_format) ||
          std::any_of(readout.codes.begin() + static_cast<std::ptrdiff_t>(before),
                      readout.codes.end(), linear_format);
      if (!held_read) {
        paste(first);  // tv's latent loses a code the window read before: it keeps its first
      } else if (!linear_read && !linear.empty() && tries.bar_sums) {
        // No linear code: the rows summed along the bars (at 17, then 49 times
        // the light) for one that tv's noise hid.
        BarSumsTry bars;
        // Judged on the first pass's latent (joint Wiener's) of the window kept,
        // not tv's: on a real label turned 8 degrees (ean13-2-05 of the real-print
        // photos, beside a second code, print and shadow) the slope found on tv's
        // latent of the window was 0, on joint Wiener's -0.14, as on the sharp scene
        // (docs/algorithms.md, "Sums along the bars").
        const imaging::Plane kept = first.part(keep0 - c0, 0, keep1 - c0, first.height);
        const imaging::Region bars_box = imaging::bar_region(kept);
        double turn = 0;
        for (const int half_rows : kBarHalfRows) {
          imaging::BarSlope slope =
              imaging::bar_slope(kept, bars_box, std::max(kSlopeHalfRows, half_rows));
          bars.slope = slope.at(kept.width / 2.0, kept.height / 2.0);
          bars.slope_change = slope.per_column * kept.width;
          // Bars that lean: a short code's rows may not cross it whole; read turned upright too.
          turn = std::abs(bars.slope) >= kMinTurnSlope ? camera_lean(direction, bars.slope) : 0;
          const std::vector<bool> across = imaging::rows_across_bars(kept, slope, half_rows);
          slope.origin_x += keep0 - c0;  // from the kept columns' coordinates to the crop's
          const DeblurOut profile =
              deblur_bar_sums(cropped.value(), slope, half_rows, frame.model, wiener_sums);
          if (!profile.ok()) break;
          bars.rows.push_back(2 * half_rows + 1);
          // The sums read where all their rows cross the bars; tv's latent elsewhere.
          auto over_rows_across = [&](const imaging::Plane& sums_latent) {
            imaging::Plane composite = patch;
            for (int y = 0; y < composite.height; ++y)
              if (across[static_cast<std::size_t>(y)])
                std::copy_n(sums_latent.row(y).begin(), composite.width, composite.row(y).begin());
            return composite;
          };
          const imaging::Plane sums = over_rows_across(profile.value().latent);
          paste(sums);
          std::vector<reader::DecodedCode> found = read_window("bar-sums", linear);
          if (found.empty() && turn != 0) found = read_window("bar-sums", linear, turn);
          // The frame shows tv's latent, and the sums' over the rows of the codes
          // they read only: the sums smear whatever else the window holds (a
          // matrix code above or below that tv or the first pass read, text)
          // along the bars' slope.
          paste(patch);
          if (!found.empty()) {
            paste(sums, found);
            bars.read = take(std::move(found), "bar-sums");
            break;
          }
          // Nothing read: tv on the same sums (noise that joint Wiener's leaves
          // hides narrow spaces), each value it reads checked against joint
          // Wiener's sums, where the budget holds another tv.
          if (!tries.tv_on_sums || !budget.take(estimate)) continue;
          const auto t1 = std::chrono::steady_clock::now();
          const DeblurOut tv_profile =
              deblur_bar_sums(cropped.value(), slope, half_rows, frame.model, tv_sums);
          bars.tv_rows.push_back(2 * half_rows + 1);
          if (tv_profile.ok()) {
            const imaging::Plane tv_composite = over_rows_across(tv_profile.value().latent);
            paste(tv_composite);
            found = read_window("tv-on-sums", linear);
            if (found.empty() && turn != 0) found = read_window("tv-on-sums", linear, turn);
            paste(sums);
            found = supported_reads(camera, std::move(found), bars.tv_checked);
            paste(patch);
            if (!found.empty()) paste(tv_composite, found);
            bars.read = take(std::move(found), "tv-on-sums");
          }
          const double tv_ms = ms_since(t1);
          own_ms += tv_ms;
          budget.settle(estimate, tv_ms, pixels);
          if (!bars.read.empty()) break;
          // Still nothing: an EAN-13 read on joint Wiener's sums by fitting
          // the symbol itself, where EAN-13 is read and the budget holds it (its
          // cost follows the row's length, not the window's pixels: settled
          // outside tv's cost model).
          const double fit_estimate = 2 * (kFitMs + kFitMsPerSample * (c1 - c0));  // two rows
          if (tries.fit && reads_ean13 && budget.take(fit_estimate)) {
            const auto t2 = std::chrono::steady_clock::now();
            const FitOnSums fit = read_sums_by_fit(profile.value().latent, across, half_rows);
            BarSumsTry::Checked verdict{fit.read.text, "EAN-13", fit.read.worst_margin,
                                        fit.read.problem, !fit.read.text.empty()};
            if (verdict.kept) {
              reader::DecodedCode code =
                  fitted_code(fit, slope, half_rows, sums.height, reads_upc_a);
              verdict.text = code.text;
              verdict.format = code.format;
              // Measured on the sums it was read on, in the camera's coordinates.
              reader::CodeCorners corners = code.quality.corners;
              for (reader::CodePoint& p : corners) {
                const auto [cx, cy] =
                    imaging::camera_point<double>(direction, p.x + c0, p.y + r0, along);
                p = {cx, cy};
              }
              paste(sums);
              reader::measure_and_place(code, camera, corners);
              paste(patch);
              if (std::none_of(readout.codes.begin(), readout.codes.end(),
                               [&](const auto& c) { return reader::same_symbol(c, code); })) {
                const std::vector<reader::DecodedCode> one = {code};
                paste(sums, one);
                bars.read = take(one, "fit");
              }
            }
            bars.fitted.push_back(std::move(verdict));
            const double fit_ms = ms_since(t2);
            own_ms += fit_ms;
            budget.settle(fit_estimate, fit_ms, 0);
          }
          if (!bars.read.empty()) break;
        }
        if (bars.read.empty() && turn != 0) read_again("tv", linear, turn);  // tv's latent, turned
        retry.bar_sums = std::move(bars);
      }
      // Nothing read: tv's prior has the print constant across the motion (bars
      // upright), which a matrix code's modules and a turned label's bars are
      // not. The window again with the same weight across as along, at
      // each of kIsotropicWeights while nothing reads and the budget holds
      // another tv; its latent stays where it reads.
      for (const double weight : kIsotropicWeights) {
        if (!tries.isotropic_tv || !held.empty() || !retry.read.empty() || !budget.take(estimate))
          break;
        const auto t1 = std::chrono::steady_clock::now();
        tv_isotropic.tv_weight_per_noise = weight;
        const DeblurOut isotropic = imaging::deblur(cropped.value(), frame.model, tv_isotropic);
        if (!retry.isotropic) retry.isotropic.emplace();
        retry.isotropic->weights.push_back(weight);
        if (isotropic.ok()) {
          paste(isotropic.value().latent);
          retry.isotropic->read = read_again("isotropic-tv", options.symbologies);
          if (retry.isotropic->read.empty()) paste(patch);
        }
        const double ms = ms_since(t1);
        own_ms += ms;
        budget.settle(estimate, ms, pixels);
      }
    }
    retry.ms = ms_since(t0);
    budget.settle(estimate, retry.ms - own_ms, pixels);
    out.retried.push_back(std::move(retry));
  }
  return out;
}

reader::BarcodeReadout read_with_cascade(const SecondPassFrame& frame,
                                         const imaging::Plane& backdrop,
                                         const reader::ReaderOptions& options,
                                         const SecondPassTries& tries, nlohmann::json& log) {
  const imaging::Plane& camera =
      frame.camera_latent != nullptr ? *frame.camera_latent : frame.motion_latent;
  const imaging::Direction direction = frame.electrons.direction();
  const auto paper = reader::find_paper_runs(frame.motion_latent);
  const auto code = reader::find_code_regions(frame.motion_latent);
  const std::vector<reader::LabelRegion> windows = options.area == reader::DecodeArea::kLabels
                                                       ? reader::regions_to_read(paper, code)
                                                       : std::vector<reader::LabelRegion>{};
  reader::BarcodeReadout readout = reader::read_codes(camera, windows, direction, options).readout;
  // Offline there is no budget: every label and code region is deblurred again,
  // read or not, so that the picture shows tv's latent wherever print lies
  // (joint Wiener's keeps the noise of its inverse filter, which readers other
  // than ZXing do not read through), except where it would lose a code.
  const auto every = retry_regions(paper, code);
  SecondPassBudget budget(kMaxSecondPassMs, 1);
  budget.add_frame(0, 0, 0);
  BeltReads reads;
  const SecondPass pass = run_second_pass(frame, every, options, tries, budget, reads, readout);
  log = pass.log(budget.credit_ms());
  if (backdrop.empty()) return readout;
  // Beyond the windows: the belt, and whatever looked like neither paper nor print.
  const int along = frame.electrons.along();
  for (int y = 0; y < frame.electrons.lines(); ++y)
    for (int n = 0; n < along; ++n) {
      const auto [x, cy] = imaging::camera_point(direction, n, y, along);
      if (std::any_of(pass.retried.begin(), pass.retried.end(),
                      [&](const WindowRetry& r) { return inside(r.window, x, cy); }))
        continue;
      const float v = backdrop.at(n, y);
      frame.motion_latent.at(n, y) = v;
      if (frame.camera_latent != nullptr) frame.camera_latent->at(x, cy) = v;
    }
  return readout;
}

}  // namespace flutterscan::session
