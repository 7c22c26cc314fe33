#pragma once
// What the controller is configured with (what SaveConfig stores), what the
// board is, and the range checks both the commands and the config loader apply.
// Freestanding C++20: no heap, no exceptions, no RTTI.

#include <array>
#include <cstdint>

#include "flutterscan/common/led_code.hpp"
#include "flutterscan/common/protocol.hpp"
#include "flutterscan/common/result.hpp"
#include "flutterscan/common/sequencer.hpp"

namespace flutterscan::firmware {

/// \brief The LEDs' hard limits, compiled into the image: no command, saved
/// configuration or image-independent setting can go above them. SetGuard,
/// SaveConfig and SetBrightness are refused above them (kAboveCeiling); a
/// saved configuration above them is tightened to them when loaded.
struct LedCeiling {
  /// Longest joined run (runs closer than min_off_time_us are one), per LED.
  std::array<std::uint32_t, kMaxLeds> max_on_time_us{};
  /// Largest energy duty: on-time x current (per mille of full scale) over the
  /// time it is spread over, per mille.
  std::array<std::uint16_t, kMaxLeds> max_duty_permille{};
  /// Largest current, per mille of the driver's full scale (SetBrightness).
  std::array<std::uint16_t, kMaxLeds> max_current_permille{};
  /// Lit runs closer than this are one run (docs/hardware.md, "Thermal guard").
  std::uint32_t min_off_time_us = 0;
};

/// Minimum off-time of the product's LEDs: three thermal time constants of the
/// die (about 1 ms for a 1 W emitter on its slug: docs/hardware.md), after
/// which less than 5 % of a pulse's temperature rise is left.
inline constexpr std::uint32_t kLedMinOffTimeUs = 3'000;

/// \brief The ceiling of the product's LED head (docs/hardware.md, "Thermal
/// guard"): 100 ms runs, 50 % energy duty, 1 A (the driver's full scale).
inline constexpr LedCeiling kProductLedCeiling{{100'000, 100'000, 100'000, 100'000},
                                               {500, 500, 500, 500},
                                               {1000, 1000, 1000, 1000},
                                               kLedMinOffTimeUs};

/// \brief Fixed facts about the board and the firmware image (GetInfo).
struct BoardConfig {
  LedPinMap pins{3, {0, 1, 2, 3}};  ///< LED enable pins on the LED GPIO port
  std::uint16_t board_id = 1;
  std::uint8_t firmware_major = 0;
  std::uint8_t firmware_minor = 1;
  std::uint8_t firmware_patch = 0;
  std::uint32_t build_id = 0;
  /// Guard limits until the host sets others: placeholders until the LED
  /// datasheet's pulse ratings are known.
  GuardLimits default_guard{{100'000, 100'000, 100'000, 100'000}, {500, 500, 500, 500}};
  /// The hard limits above every setting (default_guard must be within them).
  LedCeiling ceiling = kProductLedCeiling;
  /// True only for a board whose LEDs lose power with the MCU, so that a
  /// power-on reset means cold LEDs. The product's LEDs have their own 12 V
  /// supply (docs/hardware.md): false, so every boot starts the guard full.
  bool leds_powered_with_mcu = false;
};

/// \brief One entry of the code table.
struct StoredCode {
  bool present = false;
  LedCode code;
};

/// \brief Slot time and frame period.
struct TimingSettings {
  std::uint32_t slot_time_us = 100;
  std::uint32_t frame_period_us = 0;  ///< 0: unset (slave mode needs none)
  protocol::SlotTimeSource source = protocol::SlotTimeSource::kFixed;
};

/// \brief How exposures are started.
struct ModeSettings {
  protocol::SyncMode sync = protocol::SyncMode::kSlave;
  bool strobe_active_low = false;
};

/// \brief Everything SaveConfig stores.
struct ControllerSettings {
  std::array<StoredCode, protocol::kMaxCodes> codes{};
  std::uint8_t selected_code = protocol::kNoCode;
  TimingSettings timing;
  ModeSettings mode;
  std::array<std::uint16_t, kMaxLeds> brightness_permille{1000, 1000, 1000, 1000};
  GuardLimits guard;
};

/// \brief Factory settings for `board`: no codes, 100 us slots, slave mode, full
/// brightness and the board's default guard, each lowered to its ceiling.
ControllerSettings default_settings(const BoardConfig& board);

/// \brief SetTiming's arguments as settings; kOutOfRange on any bad field or reserved byte.
Result<TimingSettings, protocol::Status> timing_from_request(const protocol::SetTimingRequest& r);
/// \brief SetMode's arguments as settings; kOutOfRange on any bad field or reserved byte.
Result<ModeSettings, protocol::Status> mode_from_request(const protocol::SetModeRequest& r);
/// \brief kOk if every brightness of the board's LEDs is within 0..1000.
protocol::Status check_brightness(const std::array<std::uint16_t, kMaxLeds>& permille,
                                  int led_count);
/// \brief kOk if every limit of the board's LEDs is in range (on-time
/// 1..kMaxGuardOnTimeUs, duty 1..1000).
protocol::Status check_guard_limits(const GuardLimits& limits, int led_count);
/// \brief kOk if every limit of the board's LEDs is at or below `ceiling`, else kAboveCeiling.
protocol::Status check_guard_ceiling(const GuardLimits& limits, const LedCeiling& ceiling,
                                     int led_count);
/// \brief kOk if every brightness of the board's LEDs is at or below the
/// ceiling's current, else kAboveCeiling.
protocol::Status check_brightness_ceiling(const std::array<std::uint16_t, kMaxLeds>& permille,
                                          const LedCeiling& ceiling, int led_count);
/// \brief `settings` with its guard limits and brightness lowered to `ceiling`
/// wherever they are above it (a configuration saved by another image).
ControllerSettings tighten_to_ceiling(const ControllerSettings& settings,
                                      const LedCeiling& ceiling);
/// \brief kOk if `timing` is in range (the same rules as SetTiming).
protocol::Status check_timing(const TimingSettings& timing);
/// \brief kOk if a stored code fits the board (LED count, length).
protocol::Status check_stored_code(const StoredCode& code, int led_count);

}  // namespace flutterscan::firmware
