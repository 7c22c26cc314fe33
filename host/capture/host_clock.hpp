#pragma once
// The host's steady clock, nanoseconds: the clock of Frame::host_arrival_ns,
// which every backend stamps and the session measures latencies on.

#include <chrono>
#include <cstdint>

namespace flutterscan::capture {

/// \brief Now on the host's steady clock, nanoseconds.
inline std::int64_t host_now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

}  // namespace flutterscan::capture
