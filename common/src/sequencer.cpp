#include "flutterscan/common/sequencer.hpp"

namespace flutterscan {
namespace {

constexpr std::uint32_t kResetShift = 16;

std::uint32_t pin_bit(const LedPinMap& pins, int led) {
  return 1u << pins.pins[static_cast<std::size_t>(led)];
}

}  // namespace

SequencerStatus check_pin_map(const LedPinMap& pins) {
  if (pins.led_count < 1 || pins.led_count > kMaxLeds) return SequencerStatus::kBadPinMap;
  std::uint32_t used = 0;
  for (int led = 0; led < pins.led_count; ++led) {
    const std::uint8_t pin = pins.pins[static_cast<std::size_t>(led)];
    if (pin >= kGpioPinsPerPort) return SequencerStatus::kBadPinMap;
    if ((used >> pin) & 1u) return SequencerStatus::kBadPinMap;
    used |= 1u << pin;
  }
  return SequencerStatus::kOk;
}

std::uint32_t bsrr_for_mask(std::uint8_t mask, const LedPinMap& pins) {
  std::uint32_t word = 0;
  for (int led = 0; led < pins.led_count; ++led) {
    const std::uint32_t bit = pin_bit(pins, led);
    word |= ((mask >> led) & 1u) ? bit : bit << kResetShift;
  }
  return word;
}

std::uint32_t bsrr_all_off(const LedPinMap& pins) {
  return bsrr_for_mask(0, pins);
}

Result<SlotSchedule, SequencerStatus> build_slot_table(const LedCode& code,
                                                       std::uint32_t slot_time_us,
                                                       const LedPinMap& pins,
                                                       std::span<std::uint32_t> words) {
  using Out = Result<SlotSchedule, SequencerStatus>;
  if (check_pin_map(pins) != SequencerStatus::kOk) return Out::failure(SequencerStatus::kBadPinMap);
  if (code.leds() > pins.led_count) return Out::failure(SequencerStatus::kCodeHasMoreLeds);
  if (slot_time_us < kMinSlotTimeUs || slot_time_us > kMaxSlotTimeUs)
    return Out::failure(SequencerStatus::kSlotTimeOutOfRange);
  const auto length = static_cast<std::size_t>(code.length());
  if (words.size() < length + 1) return Out::failure(SequencerStatus::kBufferTooSmall);
  for (std::size_t slot = 0; slot < length; ++slot)
    words[slot] = bsrr_for_mask(code.mask(static_cast<int>(slot)), pins);
  words[length] = bsrr_all_off(pins);
  SlotSchedule schedule;
  schedule.word_count = static_cast<std::uint16_t>(length + 1);
  schedule.slot_time_us = slot_time_us;
  schedule.duration_us = static_cast<std::uint32_t>(length) * slot_time_us;
  return Out::success(schedule);
}

std::uint32_t slot_time_for_exposure(std::uint32_t exposure_us, int slots) {
  if (slots <= 0) return 0;
  return exposure_us / static_cast<std::uint32_t>(slots);
}

LedOnStats led_on_stats(const LedCode& code) {
  LedOnStats stats;
  stats.leds = code.leds();
  stats.length = code.length();
  for (int led = 0; led < code.leds(); ++led) {
    const auto k = static_cast<std::size_t>(led);
    int run = 0;
    int longest = 0;
    int leading = 0;  // run at the start of the code
    bool in_leading = true;
    for (int slot = 0; slot < code.length(); ++slot) {
      if (code.is_on(slot, led)) {
        ++run;
        ++stats.on_slots[k];
        if (in_leading) ++leading;
        if (run > longest) longest = run;
      } else {
        run = 0;
        in_leading = false;
      }
    }
    const int trailing = run;
    stats.longest_run_slots[k] = static_cast<std::uint16_t>(longest);
    stats.leading_run_slots[k] = static_cast<std::uint16_t>(leading);
    stats.trailing_run_slots[k] = static_cast<std::uint16_t>(trailing);
    // An LED on in every slot never turns off; otherwise the trailing run joins
    // the next exposure's leading run.
    const int cyclic = in_leading ? code.length() : trailing + leading;
    stats.longest_cyclic_run_slots[k] =
        static_cast<std::uint16_t>(cyclic > longest ? cyclic : longest);
  }
  return stats;
}

GuardVerdict check_led_guard(const LedOnStats& stats, std::uint32_t slot_time_us,
                             std::uint64_t period_us, const GuardLimits& limits,
                             const std::array<std::uint16_t, kMaxLeds>& current_permille) {
  const std::uint64_t duration_us = static_cast<std::uint64_t>(stats.length) * slot_time_us;
  const bool back_to_back = period_us != 0 && period_us <= duration_us;
  for (int led = 0; led < stats.leds; ++led) {
    const auto k = static_cast<std::size_t>(led);
    const std::uint16_t run =
        back_to_back ? stats.longest_cyclic_run_slots[k] : stats.longest_run_slots[k];
    const std::uint64_t on_time_us = static_cast<std::uint64_t>(run) * slot_time_us;
    if (on_time_us > limits.max_on_time_us[k])
      return {GuardStatus::kOnTimeTooLong, led, on_time_us, limits.max_on_time_us[k]};
  }
  if (period_us == 0) return {};
  const std::uint64_t effective_period_us = back_to_back ? duration_us : period_us;
  if (effective_period_us == 0) return {};
  for (int led = 0; led < stats.leds; ++led) {
    const auto k = static_cast<std::size_t>(led);
    const std::uint64_t energy =
        static_cast<std::uint64_t>(stats.on_slots[k]) * slot_time_us * current_permille[k];
    const std::uint64_t duty_permille = (energy + effective_period_us - 1) / effective_period_us;
    if (duty_permille > limits.max_duty_permille[k])
      return {GuardStatus::kDutyTooHigh, led, duty_permille, limits.max_duty_permille[k]};
  }
  return {};
}

}  // namespace flutterscan
