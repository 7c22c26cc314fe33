#include "session/second_pass.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <utility>

#include "reader/code_reading.hpp"
#include "reader/code_regions.hpp"
#include "session/second_pass_window.hpp"
#include "session/session_clock.hpp"
#include "session/session_config.hpp"
#include "session/window_tries.hpp"

namespace flutterscan::session {
namespace {

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

/// Whether work expected to take `ms` from now would end past `deadline_ns` (0: none).
bool past(std::int64_t deadline_ns, double ms) {
  return deadline_ns > 0 &&
         static_cast<double>(now_ns()) + ms * 1e6 > static_cast<double>(deadline_ns);
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

void SecondPassBudget::expect_period_ms(double period_ms) {
  const std::lock_guard lock(mutex_);
  if (!period_measured_ && period_ms > 0 && period_ms < 1000) period_ms_ = period_ms;
}

void SecondPassBudget::add_frame(std::uint64_t index, std::int64_t camera_ns,
                                 double first_pass_ms) {
  const std::lock_guard lock(mutex_);
  if (seen_frame_ && index > last_index_ && camera_ns > last_camera_ns_) {
    const double period = static_cast<double>(camera_ns - last_camera_ns_) * 1e-6 /
                          static_cast<double>(index - last_index_);
    if (period < 1000) {
      period_ms_ = period_measured_ ? 0.9 * period_ms_ + 0.1 * period : period;
      period_measured_ = true;
    }
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
    const double available = share_locked();  // per frame, all workers
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

double SecondPassBudget::frame_share_ms() const {
  const std::lock_guard lock(mutex_);
  return share_locked();
}

double SecondPassBudget::credit_ms() const {
  const std::lock_guard lock(mutex_);
  return credit_ms_;
}

double SecondPassBudget::period_ms() const {
  const std::lock_guard lock(mutex_);
  return period_ms_;
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
    for (const TryRun& t : r.tries)
      window["tries"].push_back({{"name", t.name},
                                 {"estimate_ms", std::round(t.estimate_ms * 100) / 100},
                                 {"ms", std::round(t.ms * 100) / 100},
                                 {"read", t.read}});
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
  nlohmann::json out = {{"windows", std::move(windows)},
                        {"skipped", skipped},
                        {"read_before", read_before},
                        {"credit_ms", std::round(credit_ms * 10) / 10}};
  if (past_deadline > 0) out["past_deadline"] = past_deadline;
  return out;
}

std::vector<reader::LabelRegion> unread_runs(std::span<const reader::LabelRegion> paper,
                                             const reader::BarcodeReadout& readout,
                                             imaging::Direction direction, int width, int height) {
  const std::vector<reader::DecodeWindow> windows =
      reader::decode_windows(paper, width, height, direction, kWindowMargin);
  std::vector<reader::LabelRegion> unread;
  for (std::size_t i = 0; i < paper.size(); ++i) {
    const bool read = std::any_of(readout.codes.begin(), readout.codes.end(), [&](const auto& c) {
      return in_window(windows[i], c.centre_x, c.centre_y);
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

SecondPass run_second_pass(const SecondPassFrame& frame,
                           std::span<const reader::LabelRegion> unread,
                           const reader::ReaderOptions& options, const SecondPassTries& tries,
                           SecondPassBudget& budget, BeltReads& reads,
                           reader::BarcodeReadout& readout) {
  SecondPass out;
  const std::string linear = reader::linear_symbologies(options.symbologies);
  const bool reads_ean13 = reader::names_symbology(options.symbologies, "EAN-13"),
             reads_upc_a = reader::names_symbology(options.symbologies, "UPC-A");
  for (const reader::LabelRegion& run : unread) {
    if (reads.any_over({run.begin - frame.travel_px, run.end - frame.travel_px,
                        static_cast<double>(run.across_begin),
                        static_cast<double>(run.across_end)})) {
      ++out.read_before;
      continue;
    }
    SecondPassWindow window(frame, run, options, readout, reads);
    if (!window.usable()) continue;
    // The window's estimate pays for tv and the bar sums; every other try is
    // charged its own estimate before it runs, and settled on its own.
    const double estimate = budget.estimate_ms(window.pixels());
    if (past(frame.deadline_ns, estimate)) {
      ++out.past_deadline;
      continue;
    }
    if (!budget.take(estimate)) {
      ++out.skipped;
      continue;
    }
    const auto t0 = std::chrono::steady_clock::now();
    WindowRetry retry;
    retry.window = window.window();
    double own_ms = 0;  // the tries settled on their own
    // Runs try `name` (`body`, returning the values it read) where the budget
    // holds `try_estimate`; false where it does not.
    auto paid = [&](const char* name, double try_estimate, std::size_t pixels, auto&& body) {
      if (past(frame.deadline_ns, try_estimate)) {
        ++out.past_deadline;
        return false;
      }
      if (!budget.take(try_estimate)) return false;
      const auto t1 = std::chrono::steady_clock::now();
      std::vector<std::string> read = body();
      const double ms = ms_since(t1);
      own_ms += ms;
      budget.settle(try_estimate, ms, pixels);
      retry.tries.push_back({name, try_estimate, ms, std::move(read)});
      return true;
    };
    const auto tv_began = std::chrono::steady_clock::now();
    const std::optional<imaging::Plane> tv = tv_try(window);
    retry.tries.push_back({"tv", estimate, ms_since(tv_began), window.read_values()});
    if (tv && !window.held_read()) {
      window.paste(window.first());  // tv's latent loses a code the window read before
    } else if (tv) {
      if (!window.linear_read() && !linear.empty() && tries.bar_sums) {
        BarSumsTry bars;
        const auto sums_began = std::chrono::steady_clock::now();
        const std::vector<BarSums> sums = bar_sums_try(window, *tv, linear, bars);
        retry.tries.push_back({"bar-sums", 0, ms_since(sums_began), bars.read});
        // The sums' other readings, at each count of rows while nothing reads.
        for (const BarSums& s : sums)
          if (!tries.tv_on_sums || !bars.read.empty() ||
              !paid("tv-on-sums", estimate, window.pixels(),
                    [&] { return tv_on_sums_try(window, s, *tv, linear, bars); }))
            break;
        for (const BarSums& s : sums)
          if (!tries.fit || !reads_ean13 || !bars.read.empty() ||
              !paid("fit", fit_estimate_ms(window), 0,
                    [&] { return fit_try(window, s, *tv, reads_upc_a, bars); }))
            break;
        // Nothing read: tv's latent, turned upright where the bars lean.
        if (bars.read.empty() && !sums.empty() && sums.back().turn_rad != 0)
          window.read_and_take("tv", kRowsTied, linear, sums.back().turn_rad);
        retry.bar_sums = std::move(bars);
      }
      // Nothing read, nor before: tv with an isotropic prior, at each of
      // kIsotropicWeights while nothing reads and the budget holds another.
      for (const double weight : kIsotropicWeights) {
        if (!tries.isotropic_tv || !window.held().empty() || !window.read_values().empty()) break;
        if (!paid("isotropic-tv", estimate, window.pixels(), [&] {
              if (!retry.isotropic) retry.isotropic.emplace();
              return isotropic_tv_try(window, weight, *tv, *retry.isotropic);
            }))
          break;
      }
    }
    retry.read = window.read_values();
    retry.ms = ms_since(t0);
    budget.settle(estimate, retry.ms - own_ms, window.pixels());
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
                      [&](const WindowRetry& r) { return in_window(r.window, x, cy); }))
        continue;
      const float v = backdrop.at(n, y);
      frame.motion_latent.at(n, y) = v;
      if (frame.camera_latent != nullptr) frame.camera_latent->at(x, cy) = v;
    }
  return readout;
}

}  // namespace flutterscan::session
