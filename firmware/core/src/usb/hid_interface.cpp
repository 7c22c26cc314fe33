#include "flutterscan/firmware/usb/hid_interface.hpp"

#include <algorithm>

namespace flutterscan::firmware::usb {

HidInterface::HidInterface(UsbDeviceController& controller, CommandHandler& handler,
                           std::uint8_t in_address, std::uint8_t out_address,
                           std::uint8_t interface_number)
    : controller_(controller),
      handler_(handler),
      in_address_(in_address),
      out_address_(out_address),
      interface_number_(interface_number) {}

ControlReply HidInterface::control_request(const SetupPacket& setup,
                                           std::span<std::uint8_t> buffer) {
  if ((setup.index & 0xFF) != interface_number_) return ControlReply::stall();
  switch (setup.request) {
    case kHidSetIdle:
      // wValue: duration (high byte, 4 ms units) for report ID (low byte, 0: all).
      if (setup.request_type != 0x21 || setup.length != 0 || (setup.value & 0xFF) != 0)
        return ControlReply::stall();
      idle_rate_ = static_cast<std::uint8_t>(setup.value >> 8);
      return ControlReply::status();
    case kHidGetIdle:
      if (setup.request_type != 0xA1 || setup.length == 0 || (setup.value & 0xFF) != 0 ||
          buffer.empty())
        return ControlReply::stall();
      buffer[0] = idle_rate_;
      return ControlReply::send(1);
    default:
      return ControlReply::stall();  // GET/SET_REPORT, GET/SET_PROTOCOL
  }
}

void HidInterface::set_configured(bool configured) {
  configured_ = configured;
  in_busy_ = false;
  in_halted_ = false;
  out_halted_ = false;
  out_armed_ = false;
  resend_in_flight_ = in_flight_valid_;  // endpoint closed: its packet is gone
  if (configured) {
    if (request_size_ == 0) arm_out();
    pump();
  }
}

void HidInterface::bus_reset() {
  // The host reset the bus: its transfers are void, and so are replies to
  // them. An exposure event taken from the queue is kept for the next
  // configuration (events are not answers to anything).
  request_size_ = 0;
  reply_head_ = 0;
  reply_count_ = 0;
  if (reply_in_flight_) in_flight_valid_ = false;
  reply_in_flight_ = false;
  resend_in_flight_ = in_flight_valid_;
  idle_rate_ = 0;
}

void HidInterface::out_packet(std::uint8_t address, std::span<const std::uint8_t> packet) {
  if (address != out_address_) return;
  out_armed_ = false;
  const std::size_t n = std::min(packet.size(), request_.size());
  std::fill(request_.begin(), request_.end(), std::uint8_t{0});
  std::copy_n(packet.begin(), n, request_.begin());
  // A zero-length packet is a request too (answered with a framing error).
  request_size_ = n == 0 ? 1 : n;
  request_zero_length_ = n == 0;
}

void HidInterface::in_complete(std::uint8_t address) {
  if (address != in_address_) return;
  in_busy_ = false;
  in_flight_valid_ = false;
  reply_in_flight_ = false;
  resend_in_flight_ = false;
  pump();
}

void HidInterface::endpoint_halt_changed(std::uint8_t address, bool halted) {
  if (address == in_address_) {
    in_halted_ = halted;
    if (in_busy_) {
      // Halting and un-halting both drop the queued packet (set_stall): send
      // it again once the endpoint is free.
      in_busy_ = false;
      resend_in_flight_ = in_flight_valid_;
    }
    if (!halted) pump();
  } else if (address == out_address_) {
    out_halted_ = halted;
    out_armed_ = false;  // set_stall leaves an OUT endpoint NAKing until receive()
    if (!halted && request_size_ == 0) arm_out();
  }
}

void HidInterface::poll() {
  if (!configured_) return;
  if (request_size_ != 0) handle_request();
  if (request_size_ == 0 && !out_armed_) arm_out();
  pump();
}

void HidInterface::handle_request() {
  if (reply_count_ == replies_.size()) return;  // wait: the host reads replies first
  Report& reply = replies_[(reply_head_ + reply_count_) % replies_.size()];
  reply.fill(0);
  const std::span<const std::uint8_t> request =
      request_zero_length_ ? std::span<const std::uint8_t>()
                           : std::span<const std::uint8_t>(request_).first(request_size_);
  if (handler_.handle(request, reply) != 0) ++reply_count_;
  request_size_ = 0;
  request_zero_length_ = false;
}

void HidInterface::pump() {
  if (!configured_ || in_busy_ || in_halted_) return;
  if (resend_in_flight_) {
    if (!controller_.transmit(in_address_, in_flight_)) return;
    in_busy_ = true;
    resend_in_flight_ = false;
    return;
  }
  if (reply_count_ != 0) {
    in_flight_ = replies_[reply_head_];
    if (!controller_.transmit(in_address_, in_flight_)) return;
    reply_head_ = (reply_head_ + 1) % replies_.size();
    --reply_count_;
    in_flight_valid_ = true;
    reply_in_flight_ = true;
    in_busy_ = true;
    return;
  }
  Report event{};
  if (handler_.next_event_report(event) == 0) return;
  in_flight_ = event;
  in_flight_valid_ = true;
  in_busy_ = true;
  if (!controller_.transmit(in_address_, in_flight_)) {
    in_busy_ = false;
    resend_in_flight_ = true;  // never lose the event taken from the queue
  }
}

void HidInterface::arm_out() {
  if (!configured_ || out_halted_ || out_armed_) return;
  out_armed_ = true;
  controller_.receive(out_address_);
}

}  // namespace flutterscan::firmware::usb
