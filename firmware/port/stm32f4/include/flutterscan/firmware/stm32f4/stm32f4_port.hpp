#pragma once
// The Port on the STM32F405 product board (pins in stm32f4_board.hpp).
//
// - Clock: TIM2, 32-bit, counting microseconds; its overflows (every 71.6 min)
//   extend it to 64 bits.
// - LED bank: GPIOC BSRR. Slot timer: TIM1 update event -> DMA2 stream 5
//   channel 6 -> GPIOC_BSRR, one word per slot with no CPU involved; word 0
//   lands one timer tick after the start, word i i slots later; the transfer-
//   complete interrupt (after the all-off word) reports the table done.
// - Strobe: PA5 = TIM2_CH1. IC1 captures the active edge, IC2 (on TI1) the
//   inactive one, both timestamped by the capture. TIM2's TRGO pulses on the
//   IC1 capture and is TIM1's trigger (ITR1, trigger mode): when a table is
//   pre-armed the strobe edge itself starts the slot timer (hardware, within
//   a microsecond), not an interrupt.
// - Frame timer (master / free-run): TIM2 CH3 output compare, active at each
//   frame start and inactive after the trigger pulse; OC3 drives the camera
//   trigger on PB10 (master mode) and OC3REF is TIM2's TRGO, so pre-armed
//   tables start on the frame edge in hardware too.
// - Pre-arming (prearm_slot_table): only on the controller's request, for a
//   table its guard has already accepted for any start from then on (issue
//   15, finding 3: the port used to re-arm the last table by itself and the
//   guard's refusal came after the LEDs were on). DMA and TIM1 are loaded and
//   TIM1 waits for its trigger; the edge starts it in hardware. The edge
//   interrupt records the start (its capture time) and the controller adopts
//   it from the callback (cancel_prearm); a started table is never stopped
//   for want of a confirmation. cancel_prearm from the main loop (SelectCode,
//   Disarm) first removes the trigger, then reports a start that happened
//   behind the interrupt lock (time: now, no earlier than the start). Without
//   a pre-arm the callback starts the table in software, late by the
//   interrupt latency, never before the guard decided. The controller never
//   rewrites a table the DMA may read (controller.hpp).
// - Encoder: TIM5 (32-bit) in encoder mode 3 on PA0/PA1.
// - Brightness: TIM3 CH1..CH4 PWM at 20 kHz on PC6..PC9.
// - Config pages: flash sector 1 (16 KiB at 0x08004000) and sector 11 (the
//   first 16 KiB of its 128 KiB used), erased and programmed through the flash
//   interface; SaveConfig rewrites only the one without the newest copy.
// - Watchdog: IWDG; reset cause from RCC_CSR; enter_bootloader: hand-off word
//   in SRAM, then a system reset.
// ARM only. Only one instance may exist (it owns the interrupt handlers).

#include <atomic>
#include <cstdint>
#include <span>

#include "flutterscan/common/sequencer.hpp"
#include "flutterscan/firmware/port.hpp"
#include "flutterscan/firmware/stm32f4/hardware_math.hpp"

namespace flutterscan::firmware::stm32f4 {

/// \brief Port on the STM32F405 board.
class Stm32f4Port final : public Port {
 public:
  /// \brief A port for LEDs on GPIOC `pins`, with the clocks init_clocks() set up.
  Stm32f4Port(const LedPinMap& pins, const ClockTree& clocks);

  /// \brief LEDs off, then GPIO, TIM1/2/3/5, DMA2 and their interrupts; reads
  /// and clears the reset flags.
  void init();
  /// \brief Starts the independent watchdog (cannot be stopped again).
  void start_watchdog(std::uint32_t timeout_ms);
  /// \brief True once if the hardware failed since the last call (DMA transfer
  /// error); the main loop then calls Controller::on_port_fault().
  bool take_fault() { return fault_.exchange(false, std::memory_order_relaxed); }

  // Port ------------------------------------------------------------------
  void set_listener(PortListener* listener) override { listener_ = listener; }
  std::uint64_t now_us() override;
  void write_led_bank(std::uint32_t bsrr) override;
  void set_led_brightness(int led, std::uint16_t permille) override;
  PortStatus start_slot_table(std::span<const std::uint32_t> words,
                              std::uint32_t slot_time_us) override;
  void stop_slot_table() override;
  PortStatus prearm_slot_table(std::span<const std::uint32_t> words,
                               std::uint32_t slot_time_us) override;
  PrearmStart cancel_prearm() override;
  void configure_strobe_input(bool active_low) override;
  PortStatus start_frame_timer(std::uint32_t period_us, std::uint32_t trigger_pulse_us) override;
  void stop_frame_timer() override;
  std::int32_t encoder_count() override;
  std::size_t config_page_size() override;
  PortStatus read_config_page(int copy, std::size_t offset, std::span<std::uint8_t> out) override;
  PortStatus erase_config_page(int copy) override;
  PortStatus write_config_page(int copy, std::size_t offset,
                               std::span<const std::uint8_t> data) override;
  void kick_watchdog() override;
  ResetCause reset_cause() override { return reset_cause_; }
  [[noreturn]] void enter_bootloader() override;

  // Interrupt entries (called by the handlers only) --------------------------
  void on_tim2_interrupt();
  void on_slot_dma_interrupt();

 private:
  enum class SlotState : std::uint8_t { kIdle, kPrearmed, kRunning };
  enum class FramePhase : std::uint8_t { kStart, kPulseEnd };

  std::uint64_t now_locked() const;
  /// 64-bit time of a 32-bit TIM2 capture taken at most 2^31 us ago.
  std::uint64_t extend_capture(std::uint32_t captured) const;
  /// Loads DMA and TIM1 for `words` at `setting`; TIM1 left stopped.
  void load_slot_hardware(std::span<const std::uint32_t> words, const TimerPeriod& setting);
  /// Stops TIM1 and the DMA stream; writes nothing to the LEDs.
  void stop_slot_hardware();
  void handle_strobe_capture(bool active, std::uint32_t captured);
  void handle_frame_compare();
  /// The listener callback for an edge that may have started a pre-armed table.
  template <typename Callback>
  void run_trigger_callback(std::uint64_t edge_us, Callback&& callback);

  LedPinMap pins_;
  std::uint32_t all_off_word_;
  ClockTree clocks_;
  PortListener* listener_ = nullptr;
  ResetCause reset_cause_ = ResetCause::kPowerOn;
  std::atomic<bool> fault_{false};
  bool watchdog_started_ = false;

  std::uint32_t clock_high_ = 0;  ///< TIM2 overflows

  SlotState slot_state_ = SlotState::kIdle;
  std::span<const std::uint32_t> slot_words_;  ///< the table playing or pre-armed
  TimerPeriod slot_setting_;
  PrearmStart prearm_start_;           ///< a pre-armed table an edge started, not yet taken
  bool prearm_edge_reported_ = false;  ///< its edge's callback has run

  bool strobe_active_low_ = false;
  bool frame_running_ = false;
  FramePhase frame_phase_ = FramePhase::kStart;
  std::uint32_t frame_period_us_ = 0;
  std::uint32_t frame_pulse_us_ = 0;
  std::uint32_t frame_start_lo_ = 0;  ///< TIM2 count of the current frame start

  std::uint32_t pwm_arr_ = 0;
};

}  // namespace flutterscan::firmware::stm32f4
