#pragma once
// The highest belt speed at which labels still read, by bisection on the speed
// with fresh labels at every step (docs/datasheet.md, "How a speed is measured").
//
// 1. Bracket: from a starting speed (the formula's), multiply by `growth` while
//    `step_labels` labels in a row read, or divide while one fails.
// 2. Bisect the bracket (geometric midpoints) until it is `precision` wide. A
//    step passes when all its `step_labels` labels read; it stops at the first
//    label that fails.
// 3. Verify: `final_labels` fresh labels at the highest passing speed; if any
//    fails, step the speed down by `back_off` and verify again with fresh labels
//    (at most `max_back_offs` times).
// With all of N labels read at the reported speed, the read rate is at least
// 1 - 3 / N at 95% confidence (the rule of three): N = 300 states >= 99%.

#include <cstdint>
#include <functional>

namespace flutterscan::bench {

struct SpeedSearchOptions {
  double start = 1;         ///< m/s, the first speed tried
  double min_speed = 0.01;  ///< below this a point is "does not read"
  double max_speed = 100;   ///< the search stops here ("reads at every speed tried")
  double growth = 1.6;      ///< bracketing factor
  double precision = 0.03;  ///< bisection stops when high / low <= 1 + precision
  int step_labels = 20;     ///< labels per bracketing and bisection step
  int final_labels = 300;   ///< labels that must all read at the reported speed
  double back_off = 0.9;    ///< verification failed: speed times this, verify again
  int max_back_offs = 6;
};

struct SpeedSearchResult {
  /// m/s; 0 when nothing read at min_speed; when !verified, the last speed verified
  double speed = 0;
  int final_labels = 0;   ///< labels verified at `speed` (all read)
  int labels_tried = 0;   ///< every label of the search, verification included
  int back_offs = 0;      ///< verifications that failed and stepped the speed down
  bool at_max = false;    ///< read at max_speed: the speed is a lower bound
  bool verified = false;  ///< `final_labels` of `final_labels` read at `speed`
};

/// \brief `reads(speed, label)`: whether label number `label` (each number a
/// fresh label: content, position, motion and noise drawn from it) reads at
/// `speed`. Labels are numbered from 0 upward in the order they are tried.
using LabelTrial = std::function<bool(double speed, std::uint64_t label)>;

/// \brief The highest speed at which every label of a step reads, verified on
/// `final_labels` fresh labels (see above).
SpeedSearchResult highest_reading_speed(const LabelTrial& reads, const SpeedSearchOptions& options);

}  // namespace flutterscan::bench
