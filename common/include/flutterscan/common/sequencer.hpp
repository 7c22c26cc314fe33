#pragma once
// The sequencer's pure part, shared by the firmware and the host's checks:
// turning an LED code into the GPIO BSRR words a slot timer writes, one per
// slot, and the thermal guard's verdict on a code at a slot time.
//
// BSRR (GPIO bit set/reset register, STM32 RM0090 section 8.4.7): a 32-bit
// write where bit p (0..15) drives pin p high and bit 16+p drives it low;
// pins with neither bit keep their level. All LED enable pins sit on one GPIO
// port; the pin map says which pin each LED is on.
// Freestanding C++20: no heap, no exceptions, no RTTI.

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "flutterscan/common/led_code.hpp"
#include "flutterscan/common/result.hpp"

namespace flutterscan {

/// Shortest and longest slot time, microseconds (1 us steps).
inline constexpr std::uint32_t kMinSlotTimeUs = 1;
inline constexpr std::uint32_t kMaxSlotTimeUs = 10'000;
/// Pins of one GPIO port.
inline constexpr int kGpioPinsPerPort = 16;
/// Words of the longest slot table: one per slot plus the final all-off word.
inline constexpr std::size_t kMaxSlotWords = static_cast<std::size_t>(kMaxSlots) + 1;

/// \brief Which pin of the LED GPIO port each LED's enable line is on.
struct LedPinMap {
  int led_count = 3;                          ///< LEDs on the board, 1..kMaxLeds
  std::array<std::uint8_t, kMaxLeds> pins{};  ///< pins[k]: pin of LED k (0..15), distinct
};

/// \brief Why a slot table could not be built.
enum class SequencerStatus : std::uint8_t {
  kOk,
  kBadPinMap,           ///< LED count outside 1..kMaxLeds, a pin above 15, or two LEDs on one pin
  kCodeHasMoreLeds,     ///< the code uses more LEDs than the pin map has
  kSlotTimeOutOfRange,  ///< slot time outside kMinSlotTimeUs..kMaxSlotTimeUs
  kBufferTooSmall,      ///< fewer words than code length + 1
};

/// \brief What a built slot table plays: word i at start + i * slot_time_us.
struct SlotSchedule {
  std::uint16_t word_count = 0;  ///< code length + 1 (the last word turns every LED off)
  std::uint32_t slot_time_us = 0;
  std::uint32_t duration_us = 0;  ///< code length * slot time: when the all-off word lands
};

/// \brief kOk if the pin map is usable, else kBadPinMap.
SequencerStatus check_pin_map(const LedPinMap& pins);

/// \brief The BSRR word that lights exactly the LEDs in `mask` and turns the
/// map's other LEDs off. Bits of `mask` beyond the map's LED count are ignored.
std::uint32_t bsrr_for_mask(std::uint8_t mask, const LedPinMap& pins);

/// \brief The BSRR word that turns every mapped LED off.
std::uint32_t bsrr_all_off(const LedPinMap& pins);

/// \brief Fills `words` with one BSRR word per slot of `code` followed by the
/// all-off word, and returns the schedule, or why it cannot.
Result<SlotSchedule, SequencerStatus> build_slot_table(const LedCode& code,
                                                       std::uint32_t slot_time_us,
                                                       const LedPinMap& pins,
                                                       std::span<std::uint32_t> words);

/// \brief The slot time that fits `slots` slots into an exposure of
/// `exposure_us` (rounded down so the sequence never outlasts the exposure);
/// 0 if slots is not positive.
std::uint32_t slot_time_for_exposure(std::uint32_t exposure_us, int slots);

// ---------------------------------------------------------------------------
// Thermal guard

/// \brief Per-LED limits: longest continuous on-time and largest duty cycle.
struct GuardLimits {
  std::array<std::uint32_t, kMaxLeds> max_on_time_us{};
  std::array<std::uint16_t, kMaxLeds> max_duty_permille{};  ///< of the exposure period
};

/// \brief What the guard needs to know about a code, computed once per code.
struct LedOnStats {
  int leds = 0;
  int length = 0;
  std::array<std::uint16_t, kMaxLeds> on_slots{};           ///< slots in which the LED is on
  std::array<std::uint16_t, kMaxLeds> longest_run_slots{};  ///< longest run within one exposure
  /// Longest run when exposures follow back to back (the last run joins the
  /// next exposure's first); equals `length` for an LED on in every slot.
  std::array<std::uint16_t, kMaxLeds> longest_cyclic_run_slots{};
  /// Run from the code's first slot (0 if the LED is off in slot 0); equals
  /// `length` for an LED on in every slot.
  std::array<std::uint16_t, kMaxLeds> leading_run_slots{};
  /// Run ending at the code's last slot (0 if the LED is off in the last slot);
  /// equals `length` for an LED on in every slot.
  std::array<std::uint16_t, kMaxLeds> trailing_run_slots{};
};

/// \brief On-slot counts and longest runs of every LED of `code`.
LedOnStats led_on_stats(const LedCode& code);

/// \brief The guard's verdict.
enum class GuardStatus : std::uint8_t {
  kOk,
  kOnTimeTooLong,  ///< an LED would stay on longer than its max_on_time_us
  kDutyTooHigh,    ///< an LED would be on for more than its max duty of the period
};

/// \brief A verdict with the first offending LED and the numbers that decided it.
struct GuardVerdict {
  GuardStatus status = GuardStatus::kOk;
  int led = -1;             ///< offending LED, -1 if none
  std::uint64_t value = 0;  ///< on-time in us, or duty in per mille (rounded up)
  std::uint64_t limit = 0;  ///< the limit it broke
};

/// Current of an LED at full brightness, per mille (the guard's energy unit).
inline constexpr std::uint16_t kFullCurrentPermille = 1000;
/// Every LED at full current.
inline constexpr std::array<std::uint16_t, kMaxLeds> kFullCurrent{
    kFullCurrentPermille, kFullCurrentPermille, kFullCurrentPermille, kFullCurrentPermille};

/// \brief Checks a code at `slot_time_us` against `limits`. `period_us` is the
/// time from one exposure start to the next: 0 when unknown (the duty check is
/// then skipped); a period no longer than the exposure means exposures run
/// back to back (runs wrap into the next exposure, duty over the exposure).
/// The duty is energy: on-time times `current_permille[k]` (per mille of full
/// current) over the period, so a dimmer LED may stay on longer.
GuardVerdict check_led_guard(const LedOnStats& stats, std::uint32_t slot_time_us,
                             std::uint64_t period_us, const GuardLimits& limits,
                             const std::array<std::uint16_t, kMaxLeds>& current_permille =
                                 kFullCurrent);

}  // namespace flutterscan
