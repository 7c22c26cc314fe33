#include "flutterscan/firmware/stm32f4/stm32f4_port.hpp"

#include <cstring>

#include "flutterscan/firmware/boot_decision.hpp"
#include "flutterscan/firmware/stm32f4/registers.hpp"
#include "flutterscan/firmware/stm32f4/stm32f4_board.hpp"
#include "flutterscan/firmware/stm32f4/system.hpp"

namespace flutterscan::firmware::stm32f4 {

namespace {

using namespace reg;

constexpr std::uintptr_t kLedGpio = gpio::port(kLedPort);
constexpr std::uintptr_t kLedBsrr = kLedGpio + gpio::kBsrr;
constexpr std::uintptr_t kSlotStream = dma::stream(dma::kDma2, kTim1UpRoute.stream);
constexpr int kSlotFlagShift = dma::flag_shift(kTim1UpRoute.stream);
constexpr std::uintptr_t kSlotFlagStatus = dma::kDma2 + dma::status_register(kTim1UpRoute.stream);
constexpr std::uintptr_t kSlotFlagClear = dma::kDma2 + dma::clear_register(kTim1UpRoute.stream);
/// Internal frame pulse in free-run mode (no trigger output): long enough for
/// TRGO, short enough for any frame period.
constexpr std::uint32_t kFreeRunPulseUs = 10;
/// Polls of DMA_SxCR.EN after disabling a stream (it finishes the current beat).
constexpr int kStreamStopPolls = 10'000;

/// The one port the interrupt handlers serve.
Stm32f4Port* g_port = nullptr;

void nvic_enable(int irq, std::uint8_t priority) {
  volatile std::uint8_t& ipr =
      *reinterpret_cast<volatile std::uint8_t*>(nvic::kIpr0 + static_cast<std::uintptr_t>(irq));
  ipr = static_cast<std::uint8_t>(priority << (8 - nvic::kPriorityBits));
  at(nvic::word_for(nvic::kIcpr0, irq)) = nvic::bit_for(irq);
  at(nvic::word_for(nvic::kIser0, irq)) = nvic::bit_for(irq);
}

void set_pin_mode(int port_index, int pin, std::uint32_t mode, std::uint32_t af) {
  const std::uintptr_t base = gpio::port(port_index);
  const auto p = static_cast<std::uint32_t>(pin);
  if (mode == gpio::kModeAlternate) {
    const std::uintptr_t afr = base + (p < 8 ? gpio::kAfrl : gpio::kAfrh);
    const std::uint32_t shift = 4 * (p % 8);
    modify(afr, 0xFu << shift, af << shift);
  }
  modify(base + gpio::kOspeedr, 0b11u << (2 * p), gpio::kSpeedHigh << (2 * p));
  modify(base + gpio::kModer, 0b11u << (2 * p), mode << (2 * p));
}

/// Counts since `from` on the 32-bit microsecond clock (wraps).
constexpr std::int32_t since(std::uint32_t now, std::uint32_t from) {
  return static_cast<std::int32_t>(now - from);
}

void set_oc3_mode(std::uint32_t mode) {
  modify(tim::kTim2 + tim::kCcmr2, 0b111u << tim::kOcModeShift, mode << tim::kOcModeShift);
}

}  // namespace

Stm32f4Port::Stm32f4Port(const LedPinMap& pins, const ClockTree& clocks)
    : pins_(pins), all_off_word_(bsrr_all_off(pins)), clocks_(clocks) {
  g_port = this;
}

void Stm32f4Port::init() {
  // The bootloader read the reset flags and cleared them (RMVF); it hands them
  // over in the BootRecord (boot_decision.hpp). Started without it (a
  // debugger), the record is stale or invalid and RCC_CSR still has them.
  BootRecord record;
  std::memcpy(&record, reinterpret_cast<const void*>(kBootRecordAddress), sizeof record);
  const std::uint32_t csr = at(rcc::kCsr) | reset_flags(record);
  reset_cause_ = reset_cause_from_csr(csr);
  set_bits(rcc::kCsr, rcc::kCsrRmvf);

  set_bits(rcc::kAhb1Enr,
           rcc::kAhb1EnrGpioA | rcc::kAhb1EnrGpioB | rcc::kAhb1EnrGpioC | rcc::kAhb1EnrDma2);
  set_bits(rcc::kApb1Enr, rcc::kApb1EnrTim2 | rcc::kApb1EnrTim3 | rcc::kApb1EnrTim5);
  set_bits(rcc::kApb2Enr, rcc::kApb2EnrTim1);
  (void)read(rcc::kApb2Enr);

  // LEDs: low first, then outputs (push-pull, the reset OTYPER).
  at(kLedBsrr) = all_off_word_;
  for (int led = 0; led < pins_.led_count; ++led)
    set_pin_mode(kLedPort, pins_.pins[static_cast<std::size_t>(led)], gpio::kModeOutput, 0);

  // TIM3: brightness PWM, mode 1, preloaded compares, all 0 until set.
  pwm_arr_ = brightness_pwm_arr(clocks_.tim_apb1_hz);
  at(tim::kTim3 + tim::kPsc) = 0;
  at(tim::kTim3 + tim::kArr) = pwm_arr_;
  const std::uint32_t pwm_channel = ((tim::kOcModePwm1 << tim::kOcModeShift) | tim::kOcPreload);
  at(tim::kTim3 + tim::kCcmr1) = pwm_channel | (pwm_channel << 8);
  at(tim::kTim3 + tim::kCcmr2) = pwm_channel | (pwm_channel << 8);
  for (int channel = 1; channel <= 4; ++channel) at(tim::kTim3 + tim::ccr(channel)) = 0;
  std::uint32_t ccer = 0;
  for (int channel = 1; channel <= pins_.led_count; ++channel)
    ccer |= tim::kCcerE << tim::ccer_shift(channel);
  at(tim::kTim3 + tim::kCcer) = ccer;
  at(tim::kTim3 + tim::kEgr) = tim::kEgrUg;
  at(tim::kTim3 + tim::kCr1) = tim::kCr1Arpe | tim::kCr1Cen;
  for (int led = 0; led < pins_.led_count; ++led)
    set_pin_mode(kPwmPort, kPwmFirstPin + led, gpio::kModeAlternate, kPwmAf);

  // TIM5: quadrature encoder, both inputs filtered, 32-bit count.
  at(tim::kTim5 + tim::kArr) = 0xFFFFFFFF;
  const std::uint32_t encoder_input = tim::kCcsInputOwn | (tim::kIcFilterN8 << tim::kIcFilterShift);
  at(tim::kTim5 + tim::kCcmr1) = encoder_input | (encoder_input << 8);
  at(tim::kTim5 + tim::kCcer) = 0;
  at(tim::kTim5 + tim::kSmcr) = tim::kSmsEncoderMode3;
  at(tim::kTim5 + tim::kCnt) = 0;
  at(tim::kTim5 + tim::kCr1) = tim::kCr1Cen;
  set_pin_mode(kEncoderPort, kEncoderPinA, gpio::kModeAlternate, kEncoderAf);
  set_pin_mode(kEncoderPort, kEncoderPinB, gpio::kModeAlternate, kEncoderAf);

  // TIM2: the microsecond clock, strobe capture and frame timer.
  at(tim::kTim2 + tim::kCr1) = tim::kCr1Urs;
  at(tim::kTim2 + tim::kPsc) = microsecond_prescaler(clocks_.tim_apb1_hz);
  at(tim::kTim2 + tim::kArr) = 0xFFFFFFFF;
  const std::uint32_t filter = tim::kIcFilterN8 << tim::kIcFilterShift;
  at(tim::kTim2 + tim::kCcmr1) =
      (tim::kCcsInputOwn | filter) | ((tim::kCcsInputOther | filter) << 8);       // IC1, IC2 on TI1
  at(tim::kTim2 + tim::kCcmr2) = tim::kOcModeForceInactive << tim::kOcModeShift;  // OC3
  at(tim::kTim2 + tim::kCr2) = tim::kMmsComparePulse << tim::kCr2MmsShift;
  configure_strobe_input(false);
  at(tim::kTim2 + tim::kEgr) = tim::kEgrUg;  // loads PSC; URS: no update interrupt
  at(tim::kTim2 + tim::kSr) = 0;
  at(tim::kTim2 + tim::kDier) = tim::kDierUie | tim::kDierCc1Ie | tim::kDierCc2Ie;
  at(tim::kTim2 + tim::kCr1) = tim::kCr1Urs | tim::kCr1Cen;
  set_pin_mode(kStrobePort, kStrobePin, gpio::kModeAlternate, kStrobeAf);
  set_pin_mode(kTriggerPort, kTriggerPin, gpio::kModeAlternate, kTriggerAf);

  // TIM1 + DMA2 stream 5: the slot timer, idle.
  stop_slot_hardware();
  at(kSlotStream + dma::kSxPar) = static_cast<std::uint32_t>(kLedBsrr);

  // One priority for both, so neither preempts the other's listener callback.
  nvic_enable(irq::kTim2, 1);
  nvic_enable(irq::kDma2Stream5, 1);
}

void Stm32f4Port::start_watchdog(std::uint32_t timeout_ms) {
  // Running already since the bootloader's jump (kBootWatchdogTimeoutMs): this
  // sets the application's timeout.
  watchdog_started_ = start_independent_watchdog(timeout_ms);
}

void Stm32f4Port::kick_watchdog() {
  if (watchdog_started_) at(iwdg::kKr) = iwdg::kKeyReload;
}

// ---------------------------------------------------------------------------
// Clock

std::uint64_t Stm32f4Port::now_locked() const {
  std::uint32_t high = clock_high_;
  const std::uint32_t low = at(tim::kTim2 + tim::kCnt);
  // An overflow not yet counted by the interrupt: the low half has wrapped.
  if ((at(tim::kTim2 + tim::kSr) & tim::kSrUif) != 0 && low < 0x80000000u) ++high;
  return (static_cast<std::uint64_t>(high) << 32) | low;
}

std::uint64_t Stm32f4Port::now_us() {
  InterruptLock lock;
  return now_locked();
}

std::uint64_t Stm32f4Port::extend_capture(std::uint32_t captured) const {
  const std::uint64_t now = now_locked();
  return now - static_cast<std::uint32_t>(static_cast<std::uint32_t>(now) - captured);
}

// ---------------------------------------------------------------------------
// LEDs and brightness

void Stm32f4Port::write_led_bank(std::uint32_t bsrr) {
  at(kLedBsrr) = bsrr;
}

void Stm32f4Port::set_led_brightness(int led, std::uint16_t permille) {
  if (led < 0 || led >= pins_.led_count) return;
  at(tim::kTim3 + tim::ccr(led + 1)) = brightness_compare(permille, pwm_arr_);
}

// ---------------------------------------------------------------------------
// Slot timer: TIM1 update -> DMA2 stream 5 channel 6 -> GPIOC BSRR

void Stm32f4Port::stop_slot_hardware() {
  const std::uintptr_t tim1 = tim::kTim1;
  at(tim1 + tim::kDier) = 0;  // no more DMA requests
  at(tim1 + tim::kSmcr) = 0;  // no trigger
  at(tim1 + tim::kCr1) = tim::kCr1Urs;
  clear_bits(kSlotStream + dma::kSxCr, dma::kCrEn);
  for (int i = 0; i < kStreamStopPolls && (at(kSlotStream + dma::kSxCr) & dma::kCrEn) != 0; ++i) {
  }
  at(kSlotFlagClear) = dma::kFlagAll << kSlotFlagShift;
  at(nvic::word_for(nvic::kIcpr0, irq::kDma2Stream5)) = nvic::bit_for(irq::kDma2Stream5);
  at(tim1 + tim::kSr) = 0;
}

void Stm32f4Port::load_slot_hardware(std::span<const std::uint32_t> words,
                                     const TimerPeriod& setting) {
  stop_slot_hardware();
  slot_words_ = words;
  slot_setting_ = setting;
  // DMA: memory (the table, in SRAM: DMA2 cannot reach the CCM RAM) to BSRR,
  // 32-bit, one word per request, direct mode, transfer-complete and error interrupts.
  at(kSlotStream + dma::kSxPar) = static_cast<std::uint32_t>(kLedBsrr);
  at(kSlotStream + dma::kSxM0ar) =
      static_cast<std::uint32_t>(reinterpret_cast<std::uintptr_t>(words.data()));
  at(kSlotStream + dma::kSxNdtr) = static_cast<std::uint32_t>(words.size());
  at(kSlotStream + dma::kSxFcr) = 0;
  at(kSlotStream + dma::kSxCr) =
      (static_cast<std::uint32_t>(kTim1UpRoute.channel) << dma::kCrChselShift) |
      dma::kCrPlVeryHigh | dma::kCrMsize32 | dma::kCrPsize32 | dma::kCrMinc |
      dma::kCrDirMemToPeriph | dma::kCrTcie | dma::kCrTeie;
  set_bits(kSlotStream + dma::kSxCr, dma::kCrEn);

  // TIM1: PSC and ARR loaded by UG (URS: no request for it); the counter at ARR,
  // so the first update (word 0) comes one tick after the counter starts.
  const std::uintptr_t tim1 = tim::kTim1;
  at(tim1 + tim::kPsc) = setting.psc;
  at(tim1 + tim::kArr) = setting.arr;
  at(tim1 + tim::kEgr) = tim::kEgrUg;
  at(tim1 + tim::kCnt) = setting.arr;
  at(tim1 + tim::kSr) = 0;
  at(tim1 + tim::kDier) = tim::kDierUde;
}

PortStatus Stm32f4Port::prearm_slot_table(std::span<const std::uint32_t> words,
                                          std::uint32_t slot_time_us) {
  const SlotTimerSetting setting = slot_timer_setting(slot_time_us, clocks_.tim_apb2_hz);
  if (words.empty() || words.size() > 0xFFFF || !setting.ok) return PortStatus::kError;
  InterruptLock lock;
  if (slot_state_ == SlotState::kRunning) return PortStatus::kError;  // the DMA is busy
  load_slot_hardware(words, setting.period);
  // Trigger mode from ITR1 = TIM2 TRGO: the edge sets CEN (RM0090 17.3.14).
  at(tim::kTim1 + tim::kSmcr) = (tim::kTim1TsItr1Tim2 << tim::kSmcrTsShift) | tim::kSmsTrigger;
  slot_state_ = SlotState::kPrearmed;
  prearm_start_ = {};
  return PortStatus::kOk;
}

PrearmStart Stm32f4Port::cancel_prearm() {
  InterruptLock lock;
  if (prearm_start_.started) {
    // Started by an edge whose interrupt already ran (we are in its callback,
    // or it reported the edge and the controller withdraws later).
    PrearmStart out = prearm_start_;
    out.edge_pending = !prearm_edge_reported_;
    prearm_start_ = {};
    return out;
  }
  if (slot_state_ != SlotState::kPrearmed) return {};
  at(tim::kTim1 + tim::kSmcr) = 0;  // no further trigger
  if ((at(tim::kTim1 + tim::kCr1) & tim::kCr1Cen) != 0) {
    // An edge started it and its interrupt waits behind this lock: it plays on.
    // Now is no earlier than the start (the guard decided for any start since
    // the pre-arm, and a later recorded start only makes the history stricter).
    slot_state_ = SlotState::kRunning;
    return {true, now_locked(), true};
  }
  stop_slot_hardware();
  slot_state_ = SlotState::kIdle;
  return {};
}

PortStatus Stm32f4Port::start_slot_table(std::span<const std::uint32_t> words,
                                         std::uint32_t slot_time_us) {
  const SlotTimerSetting setting = slot_timer_setting(slot_time_us, clocks_.tim_apb2_hz);
  if (words.empty() || words.size() > 0xFFFF || !setting.ok) return PortStatus::kError;
  InterruptLock lock;
  // Software start (the controller withdrew any pre-armed table first): the
  // first word one tick from now.
  load_slot_hardware(words, setting.period);
  set_bits(tim::kTim1 + tim::kCr1, tim::kCr1Cen);
  slot_state_ = SlotState::kRunning;
  prearm_start_ = {};
  return PortStatus::kOk;
}

void Stm32f4Port::stop_slot_table() {
  InterruptLock lock;
  stop_slot_hardware();
  slot_state_ = SlotState::kIdle;
  prearm_start_ = {};
}

void Stm32f4Port::on_slot_dma_interrupt() {
  const std::uint32_t flags = (at(kSlotFlagStatus) >> kSlotFlagShift) & dma::kFlagAll;
  at(kSlotFlagClear) = flags << kSlotFlagShift;
  if ((flags & (dma::kFlagTe | dma::kFlagDme)) != 0) {
    // The DMA failed mid-table: LEDs off, report through take_fault().
    stop_slot_hardware();
    write_led_bank(all_off_word_);
    slot_state_ = SlotState::kIdle;
    prearm_start_ = {};
    fault_.store(true, std::memory_order_relaxed);
    return;
  }
  if ((flags & dma::kFlagTc) == 0 || slot_state_ != SlotState::kRunning) return;
  // The all-off word is out: stop the timer before its next update.
  at(tim::kTim1 + tim::kDier) = 0;
  at(tim::kTim1 + tim::kCr1) = tim::kCr1Urs;
  slot_state_ = SlotState::kIdle;
  const std::uint64_t now = now_locked();
  // The controller pre-arms the next table itself, once its guard accepts it.
  if (listener_ != nullptr) listener_->on_slot_table_done(now);
}

template <typename Callback>
void Stm32f4Port::run_trigger_callback(std::uint64_t edge_us, Callback&& callback) {
  // Did this edge start the pre-armed table (TIM1 enabled by its trigger)?
  if (slot_state_ == SlotState::kPrearmed && (at(tim::kTim1 + tim::kCr1) & tim::kCr1Cen) != 0) {
    at(tim::kTim1 + tim::kSmcr) = 0;
    slot_state_ = SlotState::kRunning;
    prearm_start_ = {true, edge_us, false};
  }
  // The controller adopts it (cancel_prearm) from this callback; a table the
  // guard accepted is never stopped here.
  prearm_edge_reported_ = true;
  callback();
}

// ---------------------------------------------------------------------------
// Strobe input and frame timer (TIM2)

void Stm32f4Port::configure_strobe_input(bool active_low) {
  InterruptLock lock;
  strobe_active_low_ = active_low;
  // CC1 captures the active edge (and pulses TRGO), CC2 the inactive one.
  const std::uint32_t cc1 = tim::kCcerE | (active_low ? tim::kCcerP : 0u);
  const std::uint32_t cc2 = tim::kCcerE | (active_low ? 0u : tim::kCcerP);
  const std::uint32_t mask = 0xFFu;  // channels 1 and 2
  modify(tim::kTim2 + tim::kCcer, mask, (cc1 << tim::ccer_shift(1)) | (cc2 << tim::ccer_shift(2)));
}

void Stm32f4Port::handle_strobe_capture(bool active, std::uint32_t captured) {
  const std::uint64_t time = extend_capture(captured);
  if (!active) {
    if (listener_ != nullptr) listener_->on_strobe_edge(false, time);
    return;
  }
  if (frame_running_) {
    // TRGO is the frame timer's: this edge started nothing.
    if (listener_ != nullptr) listener_->on_strobe_edge(true, time);
    return;
  }
  run_trigger_callback(time, [&] {
    if (listener_ != nullptr) listener_->on_strobe_edge(true, time);
  });
}

void Stm32f4Port::handle_frame_compare() {
  const std::uintptr_t tim2 = tim::kTim2;
  if (!frame_running_) return;
  if (frame_phase_ == FramePhase::kStart) {
    // OC3REF went active at frame_start_lo_: arm the pulse end, then report the frame.
    const std::uint32_t end = frame_start_lo_ + frame_pulse_us_;
    set_oc3_mode(tim::kOcModeInactiveOnMatch);
    at(tim2 + tim::kCcr3) = end;
    frame_phase_ = FramePhase::kPulseEnd;
    const bool missed_end =
        since(at(tim2 + tim::kCnt), end) >= 0 && (at(tim2 + tim::kSr) & tim::kSrCc3If) == 0;
    const std::uint64_t time = extend_capture(frame_start_lo_);
    run_trigger_callback(time, [&] {
      if (listener_ != nullptr) listener_->on_frame_tick(time);
    });
    if (!missed_end || !frame_running_) return;
    // The interrupt came too late for the end compare: end the pulse now.
    set_oc3_mode(tim::kOcModeForceInactive);
  }
  // Pulse over: schedule the next frame start (skipping frames already past).
  std::uint32_t next = frame_start_lo_ + frame_period_us_;
  while (since(at(tim2 + tim::kCnt), next) >= 0) next += frame_period_us_;
  frame_start_lo_ = next;
  at(tim2 + tim::kCcr3) = next;
  set_oc3_mode(tim::kOcModeActiveOnMatch);
  frame_phase_ = FramePhase::kStart;
}

PortStatus Stm32f4Port::start_frame_timer(std::uint32_t period_us, std::uint32_t trigger_pulse_us) {
  if (period_us < 4 || period_us > 0x7FFFFFFF) return PortStatus::kError;
  InterruptLock lock;
  const std::uintptr_t tim2 = tim::kTim2;
  frame_period_us_ = period_us;
  // The pulse must end before the next frame starts.
  const std::uint32_t pulse = trigger_pulse_us == 0 ? kFreeRunPulseUs : trigger_pulse_us;
  frame_pulse_us_ = pulse < period_us - 2 ? pulse : period_us - 2;
  set_oc3_mode(tim::kOcModeForceInactive);
  modify(tim2 + tim::kCcer, tim::kCcerE << tim::ccer_shift(3),
         trigger_pulse_us != 0 ? tim::kCcerE << tim::ccer_shift(3) : 0u);
  modify(tim2 + tim::kCr2, tim::kCr2MmsMask, tim::kMmsOc3Ref << tim::kCr2MmsShift);
  // First frame: a couple of microseconds from now (the compare must lie ahead).
  frame_start_lo_ = at(tim2 + tim::kCnt) + 2;
  at(tim2 + tim::kCcr3) = frame_start_lo_;
  at(tim2 + tim::kSr) = ~tim::kSrCc3If;
  set_oc3_mode(tim::kOcModeActiveOnMatch);
  frame_phase_ = FramePhase::kStart;
  frame_running_ = true;
  set_bits(tim2 + tim::kDier, tim::kDierCc3Ie);
  return PortStatus::kOk;
}

void Stm32f4Port::stop_frame_timer() {
  InterruptLock lock;
  const std::uintptr_t tim2 = tim::kTim2;
  clear_bits(tim2 + tim::kDier, tim::kDierCc3Ie);
  set_oc3_mode(tim::kOcModeForceInactive);  // trigger output low
  modify(tim2 + tim::kCr2, tim::kCr2MmsMask, tim::kMmsComparePulse << tim::kCr2MmsShift);
  at(tim2 + tim::kSr) = ~tim::kSrCc3If;
  frame_running_ = false;
}

void Stm32f4Port::on_tim2_interrupt() {
  const std::uintptr_t tim2 = tim::kTim2;
  const std::uint32_t sr = at(tim2 + tim::kSr);
  if (sr & tim::kSrUif) {
    at(tim2 + tim::kSr) = ~tim::kSrUif;  // rc_w0: writing 1 leaves the others
    ++clock_high_;
  }
  const bool active = (sr & tim::kSrCc1If) != 0;
  const bool inactive = (sr & tim::kSrCc2If) != 0;
  // Reading CCRx clears CCxIF.
  const std::uint32_t active_at = active ? at(tim2 + tim::kCcr1) : 0;
  const std::uint32_t inactive_at = inactive ? at(tim2 + tim::kCcr2) : 0;
  at(tim2 + tim::kSr) = ~(tim::kSrCc1Of | tim::kSrCc2Of);
  if (active && inactive && since(active_at, inactive_at) > 0) {
    // A short pulse: the inactive edge (of the previous pulse) came first.
    handle_strobe_capture(false, inactive_at);
    handle_strobe_capture(true, active_at);
  } else {
    if (active) handle_strobe_capture(true, active_at);
    if (inactive) handle_strobe_capture(false, inactive_at);
  }
  if ((sr & tim::kSrCc3If) != 0 && (at(tim2 + tim::kDier) & tim::kDierCc3Ie) != 0) {
    at(tim2 + tim::kSr) = ~tim::kSrCc3If;
    handle_frame_compare();
  }
}

// ---------------------------------------------------------------------------
// Encoder, config page, bootloader

std::int32_t Stm32f4Port::encoder_count() {
  return static_cast<std::int32_t>(at(tim::kTim5 + tim::kCnt));
}

std::size_t Stm32f4Port::config_page_size() {
  return kConfigSize;
}

PortStatus Stm32f4Port::read_config_page(int copy, std::size_t offset,
                                         std::span<std::uint8_t> out) {
  if (copy < 0 || copy >= kConfigCopies || offset > kConfigSize ||
      out.size() > kConfigSize - offset)
    return PortStatus::kError;
  const std::uint32_t base = flash_sector_base(kConfigSectors[static_cast<std::size_t>(copy)]);
  std::memcpy(out.data(), reinterpret_cast<const void*>(static_cast<std::uintptr_t>(base + offset)),
              out.size());
  return PortStatus::kOk;
}

PortStatus Stm32f4Port::erase_config_page(int copy) {
  if (copy < 0 || copy >= kConfigCopies) return PortStatus::kError;
  kick_watchdog();  // a sector erase stalls the CPU: up to 0.5 s (16 KiB), 2 s (128 KiB)
  return flash_erase_sector(kConfigSectors[static_cast<std::size_t>(copy)]);
}

PortStatus Stm32f4Port::write_config_page(int copy, std::size_t offset,
                                          std::span<const std::uint8_t> data) {
  if (copy < 0 || copy >= kConfigCopies || offset > kConfigSize ||
      data.size() > kConfigSize - offset)
    return PortStatus::kError;
  kick_watchdog();
  const std::uint32_t base = flash_sector_base(kConfigSectors[static_cast<std::size_t>(copy)]);
  return flash_program(base + static_cast<std::uint32_t>(offset), data);
}

void Stm32f4Port::enter_bootloader() {
  asm volatile("cpsid i" ::: "memory");
  stop_slot_hardware();
  write_led_bank(all_off_word_);
  at(kBootRequestAddress) = kBootRequestMagic;
  asm volatile("dsb" ::: "memory");
  at(scb::kAircr) = scb::kAircrSystemReset;
  asm volatile("dsb" ::: "memory");
  for (;;) {
  }
}

}  // namespace flutterscan::firmware::stm32f4

extern "C" void TIM2_IRQHandler() {
  if (flutterscan::firmware::stm32f4::g_port != nullptr)
    flutterscan::firmware::stm32f4::g_port->on_tim2_interrupt();
}

extern "C" void DMA2_Stream5_IRQHandler() {
  if (flutterscan::firmware::stm32f4::g_port != nullptr)
    flutterscan::firmware::stm32f4::g_port->on_slot_dma_interrupt();
}
