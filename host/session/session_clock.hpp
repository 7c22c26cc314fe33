#pragma once
// The host clock every session stage stamps with (steady_clock, nanoseconds),
// the clock of capture::Frame::host_arrival_ns.

#include <cstdint>

#include "capture/host_clock.hpp"

namespace flutterscan::session {

/// \brief Now on the host's steady clock, nanoseconds (capture::host_now_ns).
inline std::int64_t now_ns() {
  return capture::host_now_ns();
}

/// \brief Milliseconds from `from_ns` to `to_ns`.
inline double ms_between(std::int64_t from_ns, std::int64_t to_ns) {
  return static_cast<double>(to_ns - from_ns) * 1e-6;
}

}  // namespace flutterscan::session
