#pragma once
// Checks a recorded LED transition log against a code played at a slot time.

#include <gtest/gtest.h>

#include <cstddef>
#include <cstdint>
#include <vector>

#include "flutterscan/common/led_code.hpp"
#include "flutterscan/firmware/sim/sim_port.hpp"

namespace flutterscan::firmware::test {

/// \brief Whether `log` from index `first` holds exactly one exposure of `code`
/// starting at `start_us` with `slot_us` slots: word i at start + i * slot with
/// the LEDs of slot i on, then every LED off at start + L * slot.
inline ::testing::AssertionResult plays_code(const std::vector<sim::LedTransition>& log,
                                             std::size_t first, const LedCode& code,
                                             std::uint64_t start_us, std::uint32_t slot_us) {
  const auto length = static_cast<std::size_t>(code.length());
  if (log.size() < first + length + 1)
    return ::testing::AssertionFailure()
           << "only " << log.size() - first << " writes, expected " << length + 1;
  for (std::size_t i = 0; i <= length; ++i) {
    const sim::LedTransition& t = log[first + i];
    const std::uint64_t expected_time = start_us + i * slot_us;
    const std::uint8_t expected_mask = i < length ? code.mask(static_cast<int>(i)) : 0;
    if (t.time_us != expected_time)
      return ::testing::AssertionFailure()
             << "write " << i << " at " << t.time_us << " us, expected " << expected_time;
    if (t.led_mask != expected_mask)
      return ::testing::AssertionFailure()
             << "slot " << i << ": LEDs " << int{t.led_mask} << ", expected " << int{expected_mask};
  }
  return ::testing::AssertionSuccess();
}

}  // namespace flutterscan::firmware::test
