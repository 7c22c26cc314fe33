#pragma once
// The simulation port: the Port on a virtual microsecond clock, for host unit
// tests, the HIL harness and the host's virtual controller. It plays slot
// tables exactly on time, records every LED bank write with its time and the
// resulting pin levels, generates strobe pulses and encoder counts on request,
// drives a virtual camera trigger, and holds a virtual flash page.
// It models the product port's timing (stm32f4_port.hpp): a pre-armed table
// starts on its trigger edge in hardware, before any callback; callbacks come
// set_interrupt_latency_us() after their hardware event, and not before the
// end of an interrupt lock (hold_interrupts_until: the main loop's
// InterruptLock around USB and command work). With latency 0 and no lock (the
// default) every callback runs at its event, as before.
// Host only (uses the standard library's containers).

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "flutterscan/common/sequencer.hpp"
#include "flutterscan/firmware/port.hpp"

namespace flutterscan::firmware::sim {

/// \brief One write to the LED bank.
struct LedTransition {
  std::uint64_t time_us;
  std::uint32_t bsrr;        ///< the word written
  std::uint16_t pin_levels;  ///< GPIO output levels after the write (bit p = pin p)
  std::uint8_t led_mask;     ///< LEDs on after the write (bit k = LED k, via the pin map)
};

/// \brief One camera trigger pulse driven in master mode.
struct TriggerPulse {
  std::uint64_t start_us;
  std::uint32_t width_us;
};

/// \brief Port on a virtual clock.
class SimPort final : public Port {
 public:
  /// Flash of the config pages: two 16 KB sectors of the STM32F405.
  static constexpr std::size_t kDefaultConfigPageSize = kConfigCopies * 16 * 1024;

  /// \brief A port whose LED enable pins are `pins`; `config_flash_size`
  /// bytes of erased flash, split into kConfigCopies equal config pages.
  explicit SimPort(const LedPinMap& pins, std::size_t config_flash_size = kDefaultConfigPageSize);

  // Port ------------------------------------------------------------------
  void set_listener(PortListener* listener) override { listener_ = listener; }
  std::uint64_t now_us() override { return now_us_; }
  void write_led_bank(std::uint32_t bsrr) override;
  void set_led_brightness(int led, std::uint16_t permille) override;
  PortStatus start_slot_table(std::span<const std::uint32_t> words,
                              std::uint32_t slot_time_us) override;
  void stop_slot_table() override;
  PortStatus prearm_slot_table(std::span<const std::uint32_t> words,
                               std::uint32_t slot_time_us) override;
  PrearmStart cancel_prearm() override;
  void configure_strobe_input(bool active_low) override { strobe_active_low_ = active_low; }
  PortStatus start_frame_timer(std::uint32_t period_us, std::uint32_t trigger_pulse_us) override;
  void stop_frame_timer() override { frame_period_us_ = 0; }
  std::int32_t encoder_count() override;
  std::size_t config_page_size() override { return flash_.size() / kConfigCopies; }
  PortStatus read_config_page(int copy, std::size_t offset, std::span<std::uint8_t> out) override;
  PortStatus erase_config_page(int copy) override;
  PortStatus write_config_page(int copy, std::size_t offset,
                               std::span<const std::uint8_t> data) override;
  void kick_watchdog() override { ++watchdog_kicks_; }
  ResetCause reset_cause() override { return reset_cause_; }
  void enter_bootloader() override { ++bootloader_entries_; }

  // Virtual time ------------------------------------------------------------
  /// \brief Runs every scheduled event up to and including `time_us`, in time
  /// order (at equal times: slot writes, then strobe edges, then frame ticks),
  /// then sets the clock to `time_us` (never backwards).
  void run_until(std::uint64_t time_us);
  /// \brief run_until(now + duration_us).
  void run_for(std::uint64_t duration_us) { run_until(now_us_ + duration_us); }

  // Stimuli -----------------------------------------------------------------
  /// \brief Schedules a strobe pulse: active at start_us, inactive width_us later.
  void inject_strobe(std::uint64_t start_us, std::uint32_t width_us);
  /// \brief From now on the encoder counts at `counts_per_second` (may be negative).
  void set_encoder_velocity(std::int32_t counts_per_second);
  /// \brief Adds `counts` to the encoder now.
  void add_encoder_counts(std::int32_t counts);
  /// \brief What reset_cause() reports (set before Controller::start()).
  void set_reset_cause(ResetCause cause) { reset_cause_ = cause; }
  /// \brief Callbacks come this long after their hardware event (interrupt latency).
  void set_interrupt_latency_us(std::uint32_t latency_us) { latency_us_ = latency_us; }
  /// \brief No callback before `time_us` (the main loop holds the interrupt lock
  /// until then); hardware events (pre-armed starts, slot words) go on.
  void hold_interrupts_until(std::uint64_t time_us) { lock_until_us_ = time_us; }
  /// \brief Callbacks whose hardware event happened but which have not run yet.
  bool callbacks_pending() const { return !callbacks_.empty(); }
  /// \brief A table is pre-armed and not yet started.
  bool prearmed() const { return !prearm_.words.empty(); }
  /// \brief Makes start_slot_table fail (to exercise the fault path).
  void set_slot_timer_fails(bool fails) { slot_timer_fails_ = fails; }
  /// \brief Makes start_frame_timer fail (to exercise Arm's failure path).
  void set_frame_timer_fails(bool fails) { frame_timer_fails_ = fails; }
  /// \brief Makes erase and write of the config page fail.
  void set_flash_fails(bool fails) { flash_fails_ = fails; }
  /// \brief The virtual config flash (every copy, one after the other), writable to corrupt it.
  std::span<std::uint8_t> flash_page() { return flash_; }
  /// \brief Config page `copy` alone.
  std::span<std::uint8_t> flash_page(int copy) {
    return std::span<std::uint8_t>(flash_).subspan(
        static_cast<std::size_t>(copy) * config_page_size(), config_page_size());
  }
  /// \brief Power fails during the config flash operation (erase or program)
  /// numbered `operation` from now (0: the next): an erase sets only the first
  /// `bytes` bytes of its page to 0xFF, a program writes only its first `bytes`
  /// bytes; every flash operation after it fails until restore_power().
  void lose_power_at_flash_operation(int operation, std::size_t bytes) {
    power_loss_countdown_ = operation;
    power_loss_bytes_ = bytes;
  }
  /// \brief Power is back (flash works again; what the loss left stays).
  void restore_power() {
    power_loss_countdown_ = -1;
    powered_off_ = false;
  }
  /// \brief Config flash operations (erases + programs) so far.
  int flash_operations() const { return flash_operations_; }

  // Observations -------------------------------------------------------------
  const std::vector<LedTransition>& led_transitions() const { return transitions_; }
  void clear_led_transitions() { transitions_.clear(); }
  std::uint16_t pin_levels() const { return pin_levels_; }
  /// \brief LEDs on now (bit k = LED k).
  std::uint8_t led_mask() const { return led_mask_from_pins(pin_levels_); }
  std::uint16_t led_brightness(int led) const;
  const std::vector<TriggerPulse>& trigger_pulses() const { return trigger_pulses_; }
  bool slot_table_running() const { return !table_.words.empty(); }
  /// \brief When each slot table began to play (its first word), in order.
  const std::vector<std::uint64_t>& table_starts() const { return table_starts_; }
  bool frame_timer_running() const { return frame_period_us_ != 0; }
  /// \brief The time of the earliest scheduled event (slot write, strobe
  /// edge, frame tick), or UINT64_MAX if none: the clock can jump to it.
  std::uint64_t next_event_us() const;
  bool strobe_active_low() const { return strobe_active_low_; }
  int watchdog_kicks() const { return watchdog_kicks_; }
  int bootloader_entries() const { return bootloader_entries_; }
  int flash_erases() const { return flash_erases_; }

 private:
  struct PlayingTable {
    std::span<const std::uint32_t> words;
    std::uint32_t slot_time_us = 0;
    std::uint64_t start_us = 0;
    std::size_t next_word = 0;
  };
  struct StrobeEdge {
    std::uint64_t time_us;
    bool active;
  };
  enum class CallbackKind : std::uint8_t { kStrobe, kTableDone, kFrame };
  struct Callback {
    std::uint64_t due_us;
    CallbackKind kind;
    bool active;            ///< strobe edges
    std::uint64_t time_us;  ///< the hardware event's time (what the callback reports)
    bool started_prearm;    ///< this edge started the pre-armed table
  };
  /// Runs or queues the callback of a hardware event at now.
  void raise(CallbackKind kind, bool active, bool started_prearm);
  void deliver(const Callback& callback);
  /// A trigger edge now: starts the pre-armed table if there is one; true if it did.
  bool trigger_prearmed();

  std::uint8_t led_mask_from_pins(std::uint16_t levels) const;
  void apply_bsrr(std::uint32_t bsrr);

  LedPinMap pins_;
  PortListener* listener_ = nullptr;
  std::uint64_t now_us_ = 0;
  std::uint16_t pin_levels_ = 0;
  std::vector<LedTransition> transitions_;
  std::array<std::uint16_t, kMaxLeds> brightness_{};

  PlayingTable table_;
  std::vector<std::uint64_t> table_starts_;
  PlayingTable prearm_;  ///< words empty: nothing pre-armed
  PrearmStart prearm_start_;
  bool prearm_edge_delivered_ = false;
  std::uint32_t latency_us_ = 0;
  std::uint64_t lock_until_us_ = 0;
  std::vector<Callback> callbacks_;  ///< queued, in due order
  bool slot_timer_fails_ = false;
  bool frame_timer_fails_ = false;

  std::vector<StrobeEdge> strobe_edges_;  ///< pending, sorted by time
  bool strobe_active_low_ = false;

  std::uint32_t frame_period_us_ = 0;  ///< 0: frame timer stopped
  std::uint32_t trigger_pulse_us_ = 0;
  std::uint64_t next_frame_us_ = 0;
  std::vector<TriggerPulse> trigger_pulses_;

  std::int64_t encoder_base_ = 0;
  std::uint64_t encoder_base_time_us_ = 0;
  std::int32_t encoder_velocity_ = 0;

  std::vector<std::uint8_t> flash_;
  bool flash_fails_ = false;
  int flash_erases_ = 0;
  int flash_operations_ = 0;
  int power_loss_countdown_ = -1;  ///< -1: no power loss planned
  std::size_t power_loss_bytes_ = 0;
  bool powered_off_ = false;
  /// Counts a flash operation; the bytes it may complete (all, or those of a power loss).
  std::size_t flash_operation_budget(std::size_t bytes);

  ResetCause reset_cause_ = ResetCause::kPowerOn;
  int watchdog_kicks_ = 0;
  int bootloader_entries_ = 0;
};

}  // namespace flutterscan::firmware::sim
