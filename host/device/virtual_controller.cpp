#include "device/virtual_controller.hpp"

#include <algorithm>
#include <cstddef>

#include "flutterscan/common/image_header.hpp"

namespace flutterscan::device {

namespace {

/// Longest a sequence can play: 256 slots of 10 ms.
constexpr std::uint64_t kLongestSequenceUs =
    static_cast<std::uint64_t>(protocol::kMaxCodeSlots) * protocol::kMaxSlotTimeUs;
/// Virtual-clock step while waiting for a sequence to end.
constexpr std::uint64_t kSequenceStepUs = 10;

}  // namespace

firmware::BoardConfig default_virtual_board() {
  firmware::BoardConfig board;
  board.pins = LedPinMap{3, {0, 1, 2, 3}};
  board.board_id = kBoardIdStm32f405;
  board.firmware_major = FLUTTERSCAN_VERSION_MAJOR;
  board.firmware_minor = FLUTTERSCAN_VERSION_MINOR;
  board.firmware_patch = FLUTTERSCAN_VERSION_PATCH;
  return board;
}

VirtualController::VirtualController(VirtualControllerOptions options)
    : options_(std::move(options)) {
  port_ = std::make_unique<firmware::sim::SimPort>(options_.board.pins);
  const auto page = port_->flash_page();
  std::copy_n(options_.initial_flash_page.begin(),
              std::min(options_.initial_flash_page.size(), page.size()), page.begin());
  boot_locked();
}

VirtualController::~VirtualController() {
  handler_.reset();
  controller_.reset();
}

void VirtualController::boot_locked() {
  controller_ = std::make_unique<firmware::Controller>(*port_, options_.board);
  handler_ = std::make_unique<firmware::CommandHandler>(*controller_);
  controller_->start();
  // A host reaches a real board only after USB attach debounce (100 ms, USB 2.0
  // 7.1.7.3), bus reset and enumeration; the guard counts the LEDs hot at boot
  // (firmware/core/.../controller.hpp), so the virtual board's host comes as late.
  port_->run_for(kBootToFirstRequestUs);
}

void VirtualController::poll_locked() {
  controller_->poll();
  if (port_->bootloader_entries() > 0 && !in_bootloader_) {
    // The application resets into the bootloader: its HID interface is gone.
    in_bootloader_ = true;
    replies_.clear();
  }
}

Report VirtualController::handle_locked(std::span<const std::uint8_t> report) {
  Report reply{};
  handler_->handle(report, reply);
  if (options_.reported_protocol_major != protocol::kProtocolMajor &&
      reply[0] == static_cast<std::uint8_t>(protocol::Command::kGetInfo) &&
      reply[3] == static_cast<std::uint8_t>(protocol::Status::kOk))
    reply[protocol::kHeaderSize + offsetof(protocol::InfoReply, protocol_major)] =
        options_.reported_protocol_major;
  poll_locked();
  return reply;
}

Report VirtualController::request(std::span<const std::uint8_t> report) {
  std::lock_guard lock(mutex_);
  if (!plugged_in_ || in_bootloader_ || !responsive_) return Report{};
  return handle_locked(report);
}

std::optional<Report> VirtualController::next_event_report() {
  std::lock_guard lock(mutex_);
  if (!plugged_in_ || in_bootloader_ || !responsive_) return std::nullopt;
  Report report{};
  if (handler_->next_event_report(report) == 0) return std::nullopt;
  return report;
}

bool VirtualController::write_report(std::span<const std::uint8_t> report) {
  std::lock_guard lock(mutex_);
  if (!plugged_in_ || in_bootloader_) return false;
  if (!responsive_) return true;
  (holding_replies_ ? held_replies_ : replies_).push_back(handle_locked(report));
  return true;
}

std::optional<Report> VirtualController::read_report() {
  std::lock_guard lock(mutex_);
  if (!plugged_in_ || in_bootloader_ || !responsive_) return std::nullopt;
  if (!replies_.empty()) {
    const Report reply = replies_.front();
    replies_.pop_front();
    return reply;
  }
  Report report{};
  if (handler_->next_event_report(report) == 0) return std::nullopt;
  return report;
}

void VirtualController::expose(std::uint32_t exposure_us) {
  std::lock_guard lock(mutex_);
  if (!plugged_in_ || in_bootloader_) return;
  const std::uint64_t start = port_->now_us();
  port_->inject_strobe(start, exposure_us);
  port_->run_until(start + exposure_us);
  // A sequence longer than the pulse (an overrun) still plays to its end.
  const std::uint64_t limit = start + exposure_us + kLongestSequenceUs;
  while (port_->slot_table_running() && port_->now_us() < limit) port_->run_for(kSequenceStepUs);
  poll_locked();
}

void VirtualController::add_encoder_counts(std::int32_t counts) {
  std::lock_guard lock(mutex_);
  port_->add_encoder_counts(counts);
}

// Added for the sim camera (host/capture/sim_camera.cpp).
void VirtualController::set_encoder_velocity(std::int32_t counts_per_second) {
  std::lock_guard lock(mutex_);
  port_->set_encoder_velocity(counts_per_second);
}

void VirtualController::advance_us(std::uint64_t duration_us) {
  std::lock_guard lock(mutex_);
  if (!plugged_in_) return;
  port_->run_for(duration_us);
  poll_locked();
}

std::uint64_t VirtualController::now_us() const {
  std::lock_guard lock(mutex_);
  return port_->now_us();
}

std::vector<LedTransition> VirtualController::take_led_transitions() {
  std::lock_guard lock(mutex_);
  std::vector<LedTransition> out = std::move(earlier_transitions_);
  earlier_transitions_.clear();
  const auto& recent = port_->led_transitions();
  out.insert(out.end(), recent.begin(), recent.end());
  port_->clear_led_transitions();
  return out;
}

std::uint8_t VirtualController::led_mask() const {
  std::lock_guard lock(mutex_);
  return plugged_in_ ? port_->led_mask() : 0;
}

void VirtualController::set_responsive(bool responsive) {
  std::lock_guard lock(mutex_);
  responsive_ = responsive;
}

void VirtualController::hold_replies(bool hold) {
  std::lock_guard lock(mutex_);
  holding_replies_ = hold;
  if (!hold) {
    replies_.insert(replies_.end(), held_replies_.begin(), held_replies_.end());
    held_replies_.clear();
  }
}

void VirtualController::unplug() {
  std::lock_guard lock(mutex_);
  if (!plugged_in_) return;
  plugged_in_ = false;
  replies_.clear();
  held_replies_.clear();
  const auto& recent = port_->led_transitions();
  earlier_transitions_.insert(earlier_transitions_.end(), recent.begin(), recent.end());
  port_->clear_led_transitions();
}

void VirtualController::plug_in() {
  std::lock_guard lock(mutex_);
  if (plugged_in_ && !in_bootloader_) return;
  // Power cycle: a fresh port (clock from 0, LEDs off) keeping the flash page.
  const auto recent = port_->led_transitions();
  if (plugged_in_)
    earlier_transitions_.insert(earlier_transitions_.end(), recent.begin(), recent.end());
  const auto flash = port_->flash_page();
  std::vector<std::uint8_t> saved(flash.begin(), flash.end());
  handler_.reset();
  controller_.reset();
  port_ = std::make_unique<firmware::sim::SimPort>(options_.board.pins, saved.size());
  std::copy(saved.begin(), saved.end(), port_->flash_page().begin());
  boot_locked();
  plugged_in_ = true;
  in_bootloader_ = false;
  replies_.clear();
}

bool VirtualController::plugged_in() const {
  std::lock_guard lock(mutex_);
  return plugged_in_;
}

bool VirtualController::in_bootloader() const {
  std::lock_guard lock(mutex_);
  return in_bootloader_;
}

std::vector<std::uint8_t> VirtualController::flash_page_contents() const {
  std::lock_guard lock(mutex_);
  const auto page = port_->flash_page();
  return {page.begin(), page.end()};
}

}  // namespace flutterscan::device
