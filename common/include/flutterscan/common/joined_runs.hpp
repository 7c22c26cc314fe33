#pragma once
// An LED's lit runs as its junction sees them: runs less than a minimum
// off-time apart are one run (the die has not cooled between them), the gap
// between them counted as on. The thermal guard's on-time limit applies to
// these joined runs, within one exposure and across exposures.
// Freestanding C++20: no heap, no exceptions, no RTTI.

#include <cstdint>

#include "flutterscan/common/led_code.hpp"

namespace flutterscan {

/// \brief LED `led`'s joined runs in one exposure of a code at a slot time.
/// Times are microseconds from the exposure's start.
struct JoinedRuns {
  bool lit = false;                ///< on in at least one slot
  std::uint64_t first_on_us = 0;   ///< start of the first lit slot
  std::uint64_t first_run_us = 0;  ///< the joined run starting there
  std::uint64_t last_off_us = 0;   ///< end of the last lit slot
  std::uint64_t last_run_us = 0;   ///< the joined run ending there
  std::uint64_t longest_us = 0;    ///< the longest joined run

  /// \brief Whether the whole exposure is one joined run for this LED.
  constexpr bool one_run() const { return lit && first_run_us == last_off_us - first_on_us; }
};

/// \brief LED `led`'s runs in `code` played at `slot_time_us`, runs separated by
/// less than `min_off_us` joined (an LED not in the code is not lit).
JoinedRuns joined_runs(const LedCode& code, int led, std::uint32_t slot_time_us,
                       std::uint32_t min_off_us);

}  // namespace flutterscan
