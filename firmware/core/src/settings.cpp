#include "flutterscan/firmware/settings.hpp"

#include <algorithm>

namespace flutterscan::firmware {

using protocol::Status;

namespace {

bool all_zero(const std::array<std::uint8_t, 3>& bytes) {
  return bytes[0] == 0 && bytes[1] == 0 && bytes[2] == 0;
}

bool all_zero(const std::array<std::uint8_t, 2>& bytes) {
  return bytes[0] == 0 && bytes[1] == 0;
}

}  // namespace

ControllerSettings default_settings(const BoardConfig& board) {
  ControllerSettings settings;
  settings.guard = board.default_guard;
  // Full brightness and the default guard, but never above the ceiling (a
  // board whose LEDs take less than the driver's full-scale current).
  return tighten_to_ceiling(settings, board.ceiling);
}

Status check_timing(const TimingSettings& timing) {
  if (timing.slot_time_us < protocol::kMinSlotTimeUs ||
      timing.slot_time_us > protocol::kMaxSlotTimeUs)
    return Status::kOutOfRange;
  if (timing.frame_period_us != 0 && (timing.frame_period_us < protocol::kMinFramePeriodUs ||
                                      timing.frame_period_us > protocol::kMaxFramePeriodUs))
    return Status::kOutOfRange;
  if (timing.source != protocol::SlotTimeSource::kFixed &&
      timing.source != protocol::SlotTimeSource::kFollowExposure)
    return Status::kOutOfRange;
  return Status::kOk;
}

Result<TimingSettings, Status> timing_from_request(const protocol::SetTimingRequest& r) {
  TimingSettings timing;
  timing.slot_time_us = r.slot_time_us;
  timing.frame_period_us = r.frame_period_us;
  timing.source = static_cast<protocol::SlotTimeSource>(r.slot_time_source);
  if (!all_zero(r.reserved) || check_timing(timing) != Status::kOk)
    return Result<TimingSettings, Status>::failure(Status::kOutOfRange);
  return Result<TimingSettings, Status>::success(timing);
}

Result<ModeSettings, Status> mode_from_request(const protocol::SetModeRequest& r) {
  const bool mode_known = r.sync_mode <= static_cast<std::uint8_t>(protocol::SyncMode::kFreeRun);
  if (!mode_known || r.strobe_active_low > 1 || !all_zero(r.reserved))
    return Result<ModeSettings, Status>::failure(Status::kOutOfRange);
  ModeSettings mode;
  mode.sync = static_cast<protocol::SyncMode>(r.sync_mode);
  mode.strobe_active_low = r.strobe_active_low != 0;
  return Result<ModeSettings, Status>::success(mode);
}

Status check_brightness(const std::array<std::uint16_t, kMaxLeds>& permille, int led_count) {
  for (int led = 0; led < led_count; ++led)
    if (permille[static_cast<std::size_t>(led)] > protocol::kBrightnessFullScale)
      return Status::kOutOfRange;
  return Status::kOk;
}

Status check_guard_limits(const GuardLimits& limits, int led_count) {
  for (int led = 0; led < led_count; ++led) {
    const auto k = static_cast<std::size_t>(led);
    if (limits.max_on_time_us[k] < 1 || limits.max_on_time_us[k] > protocol::kMaxGuardOnTimeUs)
      return Status::kOutOfRange;
    if (limits.max_duty_permille[k] < 1 || limits.max_duty_permille[k] > protocol::kDutyFullScale)
      return Status::kOutOfRange;
  }
  return Status::kOk;
}

Status check_guard_ceiling(const GuardLimits& limits, const LedCeiling& ceiling, int led_count) {
  for (int led = 0; led < led_count; ++led) {
    const auto k = static_cast<std::size_t>(led);
    if (limits.max_on_time_us[k] > ceiling.max_on_time_us[k] ||
        limits.max_duty_permille[k] > ceiling.max_duty_permille[k])
      return Status::kAboveCeiling;
  }
  return Status::kOk;
}

Status check_brightness_ceiling(const std::array<std::uint16_t, kMaxLeds>& permille,
                                const LedCeiling& ceiling, int led_count) {
  for (int led = 0; led < led_count; ++led) {
    const auto k = static_cast<std::size_t>(led);
    if (permille[k] > ceiling.max_current_permille[k]) return Status::kAboveCeiling;
  }
  return Status::kOk;
}

ControllerSettings tighten_to_ceiling(const ControllerSettings& settings,
                                      const LedCeiling& ceiling) {
  ControllerSettings tight = settings;
  for (std::size_t k = 0; k < static_cast<std::size_t>(kMaxLeds); ++k) {
    tight.guard.max_on_time_us[k] =
        std::min(tight.guard.max_on_time_us[k], ceiling.max_on_time_us[k]);
    tight.guard.max_duty_permille[k] =
        std::min(tight.guard.max_duty_permille[k], ceiling.max_duty_permille[k]);
    tight.brightness_permille[k] =
        std::min(tight.brightness_permille[k], ceiling.max_current_permille[k]);
  }
  return tight;
}

Status check_stored_code(const StoredCode& code, int led_count) {
  if (!code.present) return Status::kOk;
  if (code.code.leds() < 1 || code.code.leds() > led_count) return Status::kBadCode;
  if (code.code.length() < 1 || code.code.length() > kMaxSlots) return Status::kBadCode;
  return Status::kOk;
}

}  // namespace flutterscan::firmware
