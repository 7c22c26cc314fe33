#include "bench/speed_search.hpp"

#include <algorithm>
#include <cmath>

namespace flutterscan::bench {

SpeedSearchResult highest_reading_speed(const LabelTrial& reads,
                                        const SpeedSearchOptions& options) {
  SpeedSearchResult out;
  std::uint64_t next_label = 0;
  // Every label of `count` at `speed` reads; stops at the first that does not.
  const auto all_read = [&](double speed, int count) {
    for (int i = 0; i < count; ++i) {
      ++out.labels_tried;
      if (!reads(speed, next_label++)) return false;
    }
    return true;
  };

  // 1. Bracket [pass, fail].
  const double start = std::clamp(options.start, options.min_speed, options.max_speed);
  double pass = 0, fail = 0;
  if (all_read(start, options.step_labels)) {
    pass = start;
    while (fail == 0) {
      if (pass >= options.max_speed) break;
      const double v = std::min(pass * options.growth, options.max_speed);
      (all_read(v, options.step_labels) ? pass : fail) = v;
    }
  } else {
    fail = start;
    while (pass == 0 && fail > options.min_speed) {
      const double v = std::max(fail / options.growth, options.min_speed);
      (all_read(v, options.step_labels) ? pass : fail) = v;
    }
    if (pass == 0) return out;  // not even at min_speed
  }

  // 2. Bisect.
  if (fail == 0) {
    out.at_max = true;
  } else {
    while (fail / pass > 1 + options.precision) {
      const double mid = std::sqrt(pass * fail);
      (all_read(mid, options.step_labels) ? pass : fail) = mid;
    }
  }

  // 3. Verify, stepping down until every label reads.
  for (double v = pass;; v *= options.back_off) {
    out.speed = v;
    if (all_read(v, options.final_labels)) {
      out.final_labels = options.final_labels;
      out.verified = true;
      return out;
    }
    out.at_max = false;
    if (out.back_offs == options.max_back_offs || v * options.back_off < options.min_speed) break;
    ++out.back_offs;
  }
  return out;
}

}  // namespace flutterscan::bench
