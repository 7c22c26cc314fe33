#include "flutterscan/firmware/sim/sim_port.hpp"

#include <algorithm>
#include <limits>

namespace flutterscan::firmware::sim {

namespace {

/// NOR programming: cells &= data. A function of its own, never inlined, so
/// the fuzz build can leave its per-byte loop uninstrumented
/// (firmware/fuzz/coverage_ignorelist.txt).
[[gnu::noinline]] void nor_program_bytes(std::uint8_t* cells, const std::uint8_t* data,
                                         std::size_t size) {
  for (std::size_t i = 0; i < size; ++i) cells[i] = static_cast<std::uint8_t>(cells[i] & data[i]);
}

}  // namespace

SimPort::SimPort(const LedPinMap& pins, std::size_t config_page_size)
    : pins_(pins), flash_(config_page_size, 0xFF) {}

void SimPort::apply_bsrr(std::uint32_t bsrr) {
  // RM0090: a set bit wins over the reset bit of the same pin.
  const auto set = static_cast<std::uint16_t>(bsrr & 0xFFFFu);
  const auto reset = static_cast<std::uint16_t>(bsrr >> 16);
  pin_levels_ = static_cast<std::uint16_t>((pin_levels_ & ~reset) | set);
  transitions_.push_back({now_us_, bsrr, pin_levels_, led_mask_from_pins(pin_levels_)});
}

void SimPort::write_led_bank(std::uint32_t bsrr) {
  apply_bsrr(bsrr);
}

std::uint8_t SimPort::led_mask_from_pins(std::uint16_t levels) const {
  std::uint8_t mask = 0;
  for (int led = 0; led < pins_.led_count; ++led)
    if ((levels >> pins_.pins[static_cast<std::size_t>(led)]) & 1u)
      mask = static_cast<std::uint8_t>(mask | (1u << led));
  return mask;
}

void SimPort::set_led_brightness(int led, std::uint16_t permille) {
  if (led >= 0 && led < kMaxLeds) brightness_[static_cast<std::size_t>(led)] = permille;
}

std::uint16_t SimPort::led_brightness(int led) const {
  return led >= 0 && led < kMaxLeds ? brightness_[static_cast<std::size_t>(led)] : 0;
}

PortStatus SimPort::start_slot_table(std::span<const std::uint32_t> words,
                                     std::uint32_t slot_time_us) {
  if (slot_timer_fails_ || words.empty() || slot_time_us == 0) return PortStatus::kError;
  table_ = {words, slot_time_us, now_us_, 0};
  table_starts_.push_back(now_us_);
  prearm_ = {};  // the slot hardware is loaded anew
  prearm_start_ = {};
  return PortStatus::kOk;
}

PortStatus SimPort::start_frame_timer(std::uint32_t period_us, std::uint32_t trigger_pulse_us) {
  if (period_us == 0 || frame_timer_fails_) return PortStatus::kError;
  frame_period_us_ = period_us;
  trigger_pulse_us_ = trigger_pulse_us;
  next_frame_us_ = now_us_;
  return PortStatus::kOk;
}

std::int32_t SimPort::encoder_count() {
  const auto elapsed = static_cast<std::int64_t>(now_us_ - encoder_base_time_us_);
  const std::int64_t count = encoder_base_ + elapsed * encoder_velocity_ / 1'000'000;
  return static_cast<std::int32_t>(static_cast<std::uint32_t>(count));
}

void SimPort::set_encoder_velocity(std::int32_t counts_per_second) {
  const auto elapsed = static_cast<std::int64_t>(now_us_ - encoder_base_time_us_);
  encoder_base_ = encoder_base_ + elapsed * encoder_velocity_ / 1'000'000;
  encoder_base_time_us_ = now_us_;
  encoder_velocity_ = counts_per_second;
}

void SimPort::add_encoder_counts(std::int32_t counts) {
  encoder_base_ += counts;
}

void SimPort::inject_strobe(std::uint64_t start_us, std::uint32_t width_us) {
  // Each edge goes after every pending edge of its time or earlier: the order
  // a stable sort of the appended edges gives, without sorting (or its buffer).
  const auto insert = [this](StrobeEdge edge) {
    const auto at =
        std::upper_bound(strobe_edges_.begin(), strobe_edges_.end(), edge.time_us,
                         [](std::uint64_t t, const StrobeEdge& e) { return t < e.time_us; });
    strobe_edges_.insert(at, edge);
  };
  insert({start_us, true});
  insert({start_us + width_us, false});
}

std::uint64_t SimPort::next_event_us() const {
  constexpr std::uint64_t kNever = std::numeric_limits<std::uint64_t>::max();
  const std::uint64_t slot_at =
      table_.words.empty() ? kNever : table_.start_us + table_.next_word * table_.slot_time_us;
  const std::uint64_t strobe_at = strobe_edges_.empty() ? kNever : strobe_edges_.front().time_us;
  const std::uint64_t frame_at = frame_period_us_ == 0 ? kNever : next_frame_us_;
  const std::uint64_t callback_at =
      callbacks_.empty() ? kNever : std::max(callbacks_.front().due_us, lock_until_us_);
  return std::min({slot_at, strobe_at, frame_at, callback_at});
}

void SimPort::stop_slot_table() {
  table_ = {};
  prearm_ = {};
  prearm_start_ = {};
  // The port clears the table's pending done interrupt with the stream.
  std::erase_if(callbacks_, [](const Callback& c) { return c.kind == CallbackKind::kTableDone; });
}

PortStatus SimPort::prearm_slot_table(std::span<const std::uint32_t> words,
                                      std::uint32_t slot_time_us) {
  if (slot_timer_fails_ || words.empty() || slot_time_us == 0 || !table_.words.empty())
    return PortStatus::kError;
  prearm_ = {words, slot_time_us, 0, 0};
  prearm_start_ = {};
  return PortStatus::kOk;
}

PrearmStart SimPort::cancel_prearm() {
  PrearmStart out = prearm_start_;
  if (out.started) out.edge_pending = !prearm_edge_delivered_;
  prearm_ = {};
  prearm_start_ = {};
  return out;
}

bool SimPort::trigger_prearmed() {
  // A failing slot timer (set_slot_timer_fails) starts nothing in hardware either.
  if (prearm_.words.empty() || !table_.words.empty() || slot_timer_fails_) return false;
  table_ = {prearm_.words, prearm_.slot_time_us, now_us_, 0};
  table_starts_.push_back(now_us_);
  prearm_ = {};
  prearm_start_ = {true, now_us_, true};
  prearm_edge_delivered_ = false;
  return true;
}

void SimPort::raise(CallbackKind kind, bool active, bool started_prearm) {
  const Callback callback{now_us_ + latency_us_, kind, active, now_us_, started_prearm};
  if (latency_us_ == 0 && lock_until_us_ <= now_us_ && callbacks_.empty()) {
    deliver(callback);  // at its event, as without the timing model
    return;
  }
  callbacks_.push_back(callback);  // due times only grow: the queue stays in order
}

void SimPort::deliver(const Callback& callback) {
  if (callback.started_prearm) prearm_edge_delivered_ = true;
  if (listener_ == nullptr) return;
  switch (callback.kind) {
    case CallbackKind::kStrobe:
      listener_->on_strobe_edge(callback.active, callback.time_us);
      break;
    case CallbackKind::kTableDone:
      listener_->on_slot_table_done(callback.time_us);
      break;
    case CallbackKind::kFrame:
      listener_->on_frame_tick(callback.time_us);
      break;
  }
}

void SimPort::run_until(std::uint64_t time_us) {
  constexpr std::uint64_t kNever = std::numeric_limits<std::uint64_t>::max();
  for (;;) {
    const std::uint64_t slot_at =
        table_.words.empty() ? kNever : table_.start_us + table_.next_word * table_.slot_time_us;
    const std::uint64_t strobe_at = strobe_edges_.empty() ? kNever : strobe_edges_.front().time_us;
    const std::uint64_t frame_at = frame_period_us_ == 0 ? kNever : next_frame_us_;
    const std::uint64_t callback_at =
        callbacks_.empty() ? kNever : std::max(callbacks_.front().due_us, lock_until_us_);
    const std::uint64_t next = std::min({slot_at, strobe_at, frame_at, callback_at});
    if (next == kNever || next > time_us) break;
    now_us_ = std::max(now_us_, next);
    // At equal times: slot writes, strobe edges, frame ticks (the hardware),
    // then queued callbacks.
    if (slot_at == next) {
      apply_bsrr(table_.words[table_.next_word]);
      if (++table_.next_word == table_.words.size()) {
        table_ = {};
        raise(CallbackKind::kTableDone, false, false);
      }
    } else if (strobe_at == next) {
      const StrobeEdge edge = strobe_edges_.front();
      strobe_edges_.erase(strobe_edges_.begin());
      // The active edge is TIM1's trigger (TRGO) unless the frame timer owns it.
      const bool started = edge.active && frame_period_us_ == 0 && trigger_prearmed();
      raise(CallbackKind::kStrobe, edge.active, started);
    } else if (frame_at == next) {
      next_frame_us_ += frame_period_us_;
      if (trigger_pulse_us_ != 0) trigger_pulses_.push_back({now_us_, trigger_pulse_us_});
      const bool started = trigger_prearmed();
      raise(CallbackKind::kFrame, false, started);
    } else {
      const Callback callback = callbacks_.front();
      callbacks_.erase(callbacks_.begin());
      deliver(callback);
    }
  }
  now_us_ = std::max(now_us_, time_us);
}

std::size_t SimPort::flash_operation_budget(std::size_t bytes) {
  ++flash_operations_;
  if (power_loss_countdown_ < 0) return bytes;
  if (power_loss_countdown_-- > 0) return bytes;
  powered_off_ = true;
  return std::min(bytes, power_loss_bytes_);
}

PortStatus SimPort::read_config_page(int copy, std::size_t offset, std::span<std::uint8_t> out) {
  const std::size_t page = config_page_size();
  if (copy < 0 || copy >= kConfigCopies || offset > page || out.size() > page - offset)
    return PortStatus::kError;
  std::copy_n(
      flash_.begin() + static_cast<std::ptrdiff_t>(static_cast<std::size_t>(copy) * page + offset),
      out.size(), out.begin());
  return PortStatus::kOk;
}

PortStatus SimPort::erase_config_page(int copy) {
  if (flash_fails_ || powered_off_ || copy < 0 || copy >= kConfigCopies) return PortStatus::kError;
  const std::size_t page = config_page_size();
  const std::size_t erased = flash_operation_budget(page);
  auto first = flash_.begin() + static_cast<std::ptrdiff_t>(static_cast<std::size_t>(copy) * page);
  std::fill(first, first + static_cast<std::ptrdiff_t>(erased), std::uint8_t{0xFF});
  ++flash_erases_;
  return powered_off_ ? PortStatus::kError : PortStatus::kOk;
}

PortStatus SimPort::write_config_page(int copy, std::size_t offset,
                                      std::span<const std::uint8_t> data) {
  const std::size_t page = config_page_size();
  if (flash_fails_ || powered_off_ || copy < 0 || copy >= kConfigCopies || offset > page ||
      data.size() > page - offset)
    return PortStatus::kError;
  const std::size_t written = flash_operation_budget(data.size());
  // NOR flash programming only clears bits: writing over unerased bytes ANDs.
  nor_program_bytes(flash_.data() + static_cast<std::size_t>(copy) * page + offset, data.data(),
                    written);
  return powered_off_ ? PortStatus::kError : PortStatus::kOk;
}

}  // namespace flutterscan::firmware::sim
