#include "flutterscan/common/joined_runs.hpp"

namespace flutterscan {

JoinedRuns joined_runs(const LedCode& code, int led, std::uint32_t slot_time_us,
                       std::uint32_t min_off_us) {
  JoinedRuns runs;
  if (led < 0 || led >= code.leds()) return runs;
  bool in_run = false;
  std::uint64_t run_start = 0;
  std::uint64_t run_end = 0;
  auto close_run = [&runs, &run_start, &run_end] {
    const std::uint64_t length = run_end - run_start;
    if (!runs.lit) {
      runs.lit = true;
      runs.first_on_us = run_start;
      runs.first_run_us = length;
    }
    if (length > runs.longest_us) runs.longest_us = length;
    runs.last_off_us = run_end;
    runs.last_run_us = length;
  };
  for (int slot = 0; slot < code.length(); ++slot) {
    if (!code.is_on(slot, led)) continue;
    const std::uint64_t start = static_cast<std::uint64_t>(slot) * slot_time_us;
    if (in_run && start - run_end >= min_off_us) {
      close_run();
      in_run = false;
    }
    if (!in_run) {
      in_run = true;
      run_start = start;
    }
    run_end = start + slot_time_us;
  }
  if (in_run) close_run();
  return runs;
}

}  // namespace flutterscan
