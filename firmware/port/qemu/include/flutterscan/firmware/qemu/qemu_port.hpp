#pragma once
// The Port on QEMU 7.2's netduinoplus2 (STM32F405). QEMU models SysTick but not
// GPIO, RCC, DMA, TIM1/8 or the flash interface, and periodic TIM2 interrupts
// livelock it (docs in /work/shared/notes/firmware-qemu.md), so:
// - LED bank: direct GPIOA BSRR writes; QEMU logs each one with `-d unimp`,
//   which is what the QEMU test checks the slot sequence against.
// - Slot timer: SysTick interrupts at the slot period, one BSRR word each
//   (word 0 at once); between tables SysTick ticks every kIdleTickUs.
//   Deterministic under `-icount shift=N,sleep=off`.
// - Clock: microseconds counted from SysTick periods plus the current count.
// - Frame timer: checked on every SysTick interrupt (so quantised to the tick,
//   1 ms when idle); no camera trigger output.
// - Strobe and encoder: driven from the console (inject_strobe, add_encoder_counts).
// - Config page: a RAM array; watchdog: none; enter_bootloader: ignored.
// ARM only.

#include <array>
#include <atomic>
#include <cstdint>
#include <span>

#include "flutterscan/common/sequencer.hpp"
#include "flutterscan/firmware/port.hpp"
#include "flutterscan/firmware/qemu/qemu_board.hpp"

namespace flutterscan::firmware::qemu {

/// \brief Masks interrupts for its lifetime (PRIMASK), restoring the previous state.
class InterruptLock {
 public:
  InterruptLock();
  ~InterruptLock();
  InterruptLock(const InterruptLock&) = delete;
  InterruptLock& operator=(const InterruptLock&) = delete;

 private:
  std::uint32_t saved_primask_;
};

/// \brief Port on QEMU's netduinoplus2.
class QemuPort final : public Port {
 public:
  /// \brief A port whose LEDs are on GPIOA pins `pins`. Only one may exist (SysTick is one).
  explicit QemuPort(const LedPinMap& pins);

  /// \brief Enables clocks, makes the LED pins outputs, starts the SysTick tick.
  void init();

  // Port ------------------------------------------------------------------
  void set_listener(PortListener* listener) override { listener_ = listener; }
  std::uint64_t now_us() override;
  void write_led_bank(std::uint32_t bsrr) override;
  void set_led_brightness(int led, std::uint16_t permille) override;
  PortStatus start_slot_table(std::span<const std::uint32_t> words,
                              std::uint32_t slot_time_us) override;
  void stop_slot_table() override;
  /// \brief Not supported (no hardware trigger path on QEMU): every exposure
  /// starts from its edge's callback.
  PortStatus prearm_slot_table(std::span<const std::uint32_t>, std::uint32_t) override {
    return PortStatus::kError;
  }
  PrearmStart cancel_prearm() override { return {}; }
  void configure_strobe_input(bool active_low) override { strobe_active_low_ = active_low; }
  PortStatus start_frame_timer(std::uint32_t period_us, std::uint32_t trigger_pulse_us) override;
  void stop_frame_timer() override;
  std::int32_t encoder_count() override { return encoder_.load(std::memory_order_relaxed); }
  std::size_t config_page_size() override { return kConfigPageSize; }
  PortStatus read_config_page(int copy, std::size_t offset, std::span<std::uint8_t> out) override;
  PortStatus erase_config_page(int copy) override;
  PortStatus write_config_page(int copy, std::size_t offset,
                               std::span<const std::uint8_t> data) override;
  void kick_watchdog() override {}
  ResetCause reset_cause() override { return ResetCause::kPowerOn; }
  void enter_bootloader() override {}

  // Console stimuli -----------------------------------------------------------
  /// \brief The strobe input's level changed to `high` (edge reported with its polarity).
  void inject_strobe(bool high);
  /// \brief Adds `counts` to the encoder.
  void add_encoder_counts(std::int32_t counts);

  // Observations ----------------------------------------------------------------
  /// \brief BSRR writes made since start (what QEMU's unimp log shows).
  std::uint32_t led_write_count() const { return led_writes_.load(std::memory_order_relaxed); }
  bool strobe_active_low() const { return strobe_active_low_; }
  std::uint16_t led_brightness(int led) const;

  /// \brief The SysTick exception (called from SysTick_Handler only).
  void on_systick();

 private:
  /// Reprograms SysTick to interrupt every `period_us`, from now on. Interrupts masked.
  void set_tick_period_locked(std::uint32_t period_us);
  /// now_us() with interrupts already masked.
  std::uint64_t now_locked() const;

  LedPinMap pins_;
  PortListener* listener_ = nullptr;

  // Time: elapsed_us_ counts whole SysTick periods, tick_period_us_ is the current one.
  std::uint64_t elapsed_us_ = 0;
  std::uint32_t tick_period_us_ = kIdleTickUs;

  // Slot table in play (next_word_ == words_.size(): none).
  std::span<const std::uint32_t> words_;
  std::size_t next_word_ = 0;
  bool table_running_ = false;

  std::uint32_t frame_period_us_ = 0;  ///< 0: frame timer stopped
  std::uint64_t next_frame_us_ = 0;

  bool strobe_active_low_ = false;
  std::atomic<std::int32_t> encoder_{0};
  std::atomic<std::uint32_t> led_writes_{0};
  std::array<std::uint16_t, kMaxLeds> brightness_{};
  std::array<std::array<std::uint8_t, kConfigPageSize>, kConfigCopies>
      config_page_;  ///< zero-initialised in .bss, erased in the constructor
};

}  // namespace flutterscan::firmware::qemu
