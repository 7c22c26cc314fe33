#include "flutterscan/firmware/qemu/qemu_port.hpp"

#include <algorithm>
#include <cstring>

#include "flutterscan/firmware/qemu/registers.hpp"

namespace flutterscan::firmware::qemu {

namespace {

constexpr std::uint32_t kCyclesPerUs = kSysClockHz / 1'000'000;

/// The one port SysTick_Handler serves.
QemuPort* g_systick_port = nullptr;

}  // namespace

InterruptLock::InterruptLock() {
  std::uint32_t primask;
  asm volatile("mrs %0, primask\n\tcpsid i" : "=r"(primask)::"memory");
  saved_primask_ = primask;
}

InterruptLock::~InterruptLock() {
  asm volatile("msr primask, %0" ::"r"(saved_primask_) : "memory");
}

QemuPort::QemuPort(const LedPinMap& pins) : pins_(pins) {
  for (auto& page : config_page_) page.fill(0xFF);  // erased flash
  g_systick_port = this;
}

void QemuPort::init() {
  reg::set_bits(reg::rcc::kAhb1Enr, reg::rcc::kAhb1EnrGpioA);
  for (int led = 0; led < pins_.led_count; ++led) {
    const std::uint32_t shift = 2u * pins_.pins[static_cast<std::size_t>(led)];
    reg::modify(reg::gpioa::kModer, 0b11u << shift, reg::gpioa::kModeOutput << shift);
  }
  InterruptLock lock;
  set_tick_period_locked(kIdleTickUs);
}

// ---------------------------------------------------------------------------
// Clock and SysTick

void QemuPort::set_tick_period_locked(std::uint32_t period_us) {
  elapsed_us_ = now_locked();
  reg::at(reg::scb::kIcsr) = reg::scb::kIcsrPendStClr;  // now_locked() counted a pending wrap
  reg::at(reg::systick::kCtrl) = 0;
  reg::at(reg::systick::kLoad) = period_us * kCyclesPerUs - 1u;
  reg::at(reg::systick::kVal) = 0;  // any write clears it: reload on the next clock
  tick_period_us_ = period_us;
  reg::at(reg::systick::kCtrl) =
      reg::systick::kCtrlEnable | reg::systick::kCtrlTickInt | reg::systick::kCtrlClkSource;
}

std::uint64_t QemuPort::now_locked() const {
  if ((reg::at(reg::systick::kCtrl) & reg::systick::kCtrlEnable) == 0) return elapsed_us_;
  std::uint64_t base = elapsed_us_;
  const std::uint32_t load = reg::at(reg::systick::kLoad);
  std::uint32_t value = reg::at(reg::systick::kVal);
  if (reg::at(reg::scb::kIcsr) & reg::scb::kIcsrPendStSet) {
    // Wrapped, interrupt not yet taken: count that period and re-read the counter.
    base += tick_period_us_;
    value = reg::at(reg::systick::kVal);
  }
  const std::uint32_t counted = value == 0 ? 0 : load - value;
  return base + counted / kCyclesPerUs;
}

std::uint64_t QemuPort::now_us() {
  InterruptLock lock;
  return now_locked();
}

void QemuPort::on_systick() {
  elapsed_us_ += tick_period_us_;
  const std::uint64_t now = elapsed_us_;
  if (table_running_) {
    if (next_word_ < words_.size()) write_led_bank(words_[next_word_++]);
    if (next_word_ >= words_.size()) {
      table_running_ = false;
      set_tick_period_locked(kIdleTickUs);
      if (listener_ != nullptr) listener_->on_slot_table_done(now);
    }
  }
  if (frame_period_us_ != 0 && now >= next_frame_us_) {
    next_frame_us_ += frame_period_us_;
    if (next_frame_us_ <= now) next_frame_us_ = now + frame_period_us_;  // missed ticks
    if (listener_ != nullptr) listener_->on_frame_tick(now);
  }
}

// ---------------------------------------------------------------------------
// LEDs and slot timer

void QemuPort::write_led_bank(std::uint32_t bsrr) {
  reg::at(reg::gpioa::kBsrr) = bsrr;
  led_writes_.store(led_writes_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
}

void QemuPort::set_led_brightness(int led, std::uint16_t permille) {
  // No PWM in QEMU: remembered only.
  if (led >= 0 && led < kMaxLeds) brightness_[static_cast<std::size_t>(led)] = permille;
}

std::uint16_t QemuPort::led_brightness(int led) const {
  return led >= 0 && led < kMaxLeds ? brightness_[static_cast<std::size_t>(led)] : 0;
}

PortStatus QemuPort::start_slot_table(std::span<const std::uint32_t> words,
                                      std::uint32_t slot_time_us) {
  if (words.empty() || slot_time_us == 0 ||
      slot_time_us > (reg::systick::kMaxReload + 1u) / kCyclesPerUs)
    return PortStatus::kError;
  InterruptLock lock;
  words_ = words;
  write_led_bank(words_[0]);
  next_word_ = 1;
  table_running_ = true;
  set_tick_period_locked(slot_time_us);
  return PortStatus::kOk;
}

void QemuPort::stop_slot_table() {
  InterruptLock lock;
  if (!table_running_) return;
  table_running_ = false;
  words_ = {};
  next_word_ = 0;
  set_tick_period_locked(kIdleTickUs);
}

PortStatus QemuPort::start_frame_timer(std::uint32_t period_us, std::uint32_t) {
  if (period_us == 0) return PortStatus::kError;
  InterruptLock lock;
  frame_period_us_ = period_us;
  next_frame_us_ = now_locked();  // first tick at the next SysTick interrupt
  return PortStatus::kOk;
}

void QemuPort::stop_frame_timer() {
  InterruptLock lock;
  frame_period_us_ = 0;
}

// ---------------------------------------------------------------------------
// Console stimuli

void QemuPort::inject_strobe(bool high) {
  InterruptLock lock;
  if (listener_ != nullptr) listener_->on_strobe_edge(high != strobe_active_low_, now_locked());
}

void QemuPort::add_encoder_counts(std::int32_t counts) {
  const auto sum = static_cast<std::uint32_t>(encoder_.load(std::memory_order_relaxed)) +
                   static_cast<std::uint32_t>(counts);
  encoder_.store(static_cast<std::int32_t>(sum), std::memory_order_relaxed);
}

// ---------------------------------------------------------------------------
// Config page (RAM)

PortStatus QemuPort::read_config_page(int copy, std::size_t offset, std::span<std::uint8_t> out) {
  if (copy < 0 || copy >= kConfigCopies || offset > kConfigPageSize ||
      out.size() > kConfigPageSize - offset)
    return PortStatus::kError;
  std::memcpy(out.data(), config_page_[static_cast<std::size_t>(copy)].data() + offset, out.size());
  return PortStatus::kOk;
}

PortStatus QemuPort::erase_config_page(int copy) {
  if (copy < 0 || copy >= kConfigCopies) return PortStatus::kError;
  config_page_[static_cast<std::size_t>(copy)].fill(0xFF);
  return PortStatus::kOk;
}

PortStatus QemuPort::write_config_page(int copy, std::size_t offset,
                                       std::span<const std::uint8_t> data) {
  if (copy < 0 || copy >= kConfigCopies || offset > kConfigPageSize ||
      data.size() > kConfigPageSize - offset)
    return PortStatus::kError;
  // Flash programming only clears bits.
  auto& page = config_page_[static_cast<std::size_t>(copy)];
  for (std::size_t i = 0; i < data.size(); ++i) page[offset + i] &= data[i];
  return PortStatus::kOk;
}

}  // namespace flutterscan::firmware::qemu

extern "C" void SysTick_Handler() {
  if (flutterscan::firmware::qemu::g_systick_port != nullptr)
    flutterscan::firmware::qemu::g_systick_port->on_systick();
}
