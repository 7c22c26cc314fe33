#pragma once
// Helpers for the session stages' unit tests: exposures with their frames on
// one clock.

#include "capture/camera_source.hpp"
#include "session/frame_matcher.hpp"

namespace flutterscan::session::testing {

inline constexpr std::uint64_t kPeriodUs = 10'000;

/// \brief Exposure k (0-based): controller counter k + 1, slot 0 at 1000 + k x 10 ms,
/// 52 slots of 100 us, `encoder_delta` counts.
inline ExposureRecord exposure(int k, std::int32_t encoder_delta = 40) {
  ExposureRecord e;
  e.frame_counter = static_cast<std::uint32_t>(k + 1);
  e.start_us = 1000 + static_cast<std::uint64_t>(k) * kPeriodUs;
  e.encoder_delta = encoder_delta;
  e.slot_time_us = 100;
  e.slot_count = 52;
  return e;
}

/// \brief The camera's frame of exposure k: sequence k, its clock the controller's in ns.
inline capture::Frame frame_of(int k, std::int64_t arrival_ns = 1) {
  capture::Frame f;
  f.sequence = static_cast<std::uint64_t>(k);
  f.timestamp_ns = static_cast<std::int64_t>(exposure(k).start_us) * 1000;
  f.host_arrival_ns = arrival_ns;
  f.format.width = 4;
  f.format.height = 2;
  f.format.pixel_format = capture::PixelFormat::kMono8;
  f.data.assign(8, 0);
  return f;
}

}  // namespace flutterscan::session::testing
