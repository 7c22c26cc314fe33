#include "flutterscan/firmware/sim/sim_usb_controller.hpp"

#include <algorithm>

namespace flutterscan::firmware::sim {

// ---------------------------------------------------------------------------
// Host side

ControlResult SimUsbController::control_transfer(std::uint8_t request_type, std::uint8_t request,
                                                 std::uint16_t value, std::uint16_t index,
                                                 std::uint16_t length,
                                                 std::span<const std::uint8_t> out_data) {
  const auto setup = usb::SetupPacket{request_type, request, value, index, length}.bytes();
  return control_transfer(setup, out_data);
}

ControlResult SimUsbController::control_transfer(std::span<const std::uint8_t, 8> setup_bytes,
                                                 std::span<const std::uint8_t> out_data) {
  ControlResult result;
  if (device_ == nullptr) {
    result.stalled = true;
    return result;
  }
  const usb::SetupPacket setup = usb::SetupPacket::parse(setup_bytes);
  ep0_stage_ = Ep0Stage::kIdle;  // this SETUP aborts a packet-level transfer too
  ep0_answer_ = Ep0Answer::kNone;
  ep0_answers_ = 0;
  ep0_in_.clear();
  device_->on_setup(setup);

  if (ep0_answers_ != 1) ++ep0_protocol_errors_;
  switch (ep0_answer_) {
    case Ep0Answer::kNone:
    case Ep0Answer::kStall:
      result.stalled = true;
      return result;
    case Ep0Answer::kTransmit:
      if (!setup.is_in()) ++ep0_protocol_errors_;
      // A zero-length packet must end a data stage shorter than wLength that
      // is a multiple of the packet size (the host would wait for more), and only then.
      if (ep0_zero_length_end_ !=
          (ep0_in_.size() < setup.length && ep0_in_.size() % usb::kEp0MaxPacket == 0))
        ++ep0_protocol_errors_;
      result.data.assign(ep0_in_.begin(),
                         ep0_in_.begin() + static_cast<std::ptrdiff_t>(std::min<std::size_t>(
                                               ep0_in_.size(), setup.length)));
      device_->on_ep0_status_complete();  // the host's zero-length OUT status packet
      return result;
    case Ep0Answer::kStatus:
      if (setup.is_in() && setup.length != 0) ++ep0_protocol_errors_;
      device_->on_ep0_status_complete();
      return result;
    case Ep0Answer::kReceive: {
      if (setup.is_in()) ++ep0_protocol_errors_;
      // The host sends wLength bytes (fewer if it has fewer: a short data stage).
      const std::size_t n = std::min(out_data.size(), ep0_out_buffer_.size());
      std::copy_n(out_data.begin(), n, ep0_out_buffer_.begin());
      ep0_answer_ = Ep0Answer::kNone;
      ep0_answers_ = 0;
      device_->on_ep0_out_complete(n);
      if (ep0_answers_ != 1) ++ep0_protocol_errors_;
      if (ep0_answer_ != Ep0Answer::kStatus) {
        result.stalled = true;
        return result;
      }
      device_->on_ep0_status_complete();
      return result;
    }
  }
  return result;
}

OutResult SimUsbController::interrupt_out(std::uint8_t address,
                                          std::span<const std::uint8_t> packet) {
  Endpoint* ep = find(address);
  if (ep == nullptr || !ep->open || usb::is_in_endpoint(address) ||
      packet.size() > ep->config.max_packet)
    return OutResult::kNoEndpoint;
  if (ep->halted) return OutResult::kStall;
  if (!ep->armed) return OutResult::kNak;
  ep->armed = false;
  if (device_ != nullptr) device_->on_out_packet(address, packet);
  return OutResult::kAck;
}

std::optional<std::vector<std::uint8_t>> SimUsbController::interrupt_in(std::uint8_t address) {
  Endpoint* ep = find(address);
  if (ep == nullptr || !ep->open || ep->halted || !ep->packet) return std::nullopt;
  std::vector<std::uint8_t> packet = std::move(*ep->packet);
  ep->packet.reset();
  if (device_ != nullptr) device_->on_in_complete(address);
  return packet;
}

void SimUsbController::bus_reset() {
  address_ = 0;
  ep0_stage_ = Ep0Stage::kIdle;
  endpoints_.clear();
  if (device_ != nullptr) device_->on_bus_reset();
}

bool SimUsbController::endpoint_open(std::uint8_t address) const {
  const Endpoint* ep = find(address);
  return ep != nullptr && ep->open;
}

bool SimUsbController::endpoint_halted(std::uint8_t address) const {
  const Endpoint* ep = find(address);
  return ep != nullptr && ep->open && ep->halted;
}

bool SimUsbController::in_packet_waiting(std::uint8_t address) const {
  const Endpoint* ep = find(address);
  return ep != nullptr && ep->open && ep->packet.has_value();
}

// ---------------------------------------------------------------------------
// UsbDeviceController

SimUsbController::Endpoint* SimUsbController::find(std::uint8_t address) {
  const auto it = endpoints_.find(address);
  return it == endpoints_.end() ? nullptr : &it->second;
}

const SimUsbController::Endpoint* SimUsbController::find(std::uint8_t address) const {
  const auto it = endpoints_.find(address);
  return it == endpoints_.end() ? nullptr : &it->second;
}

void SimUsbController::open_endpoint(const usb::EndpointConfig& endpoint) {
  Endpoint& ep = endpoints_[endpoint.address];
  ep = Endpoint{};
  ep.config = endpoint;
  ep.open = true;
}

void SimUsbController::close_endpoint(std::uint8_t address) {
  Endpoint* ep = find(address);
  if (ep == nullptr) return;
  const usb::EndpointConfig config = ep->config;
  *ep = Endpoint{};
  ep->config = config;
}

void SimUsbController::set_stall(std::uint8_t address, bool stalled) {
  Endpoint* ep = find(address);
  if (ep == nullptr || !ep->open) return;
  ep->halted = stalled;
  ep->packet.reset();
  ep->armed = false;
}

bool SimUsbController::transmit(std::uint8_t address, std::span<const std::uint8_t> packet) {
  Endpoint* ep = find(address);
  if (ep == nullptr || !ep->open || ep->halted || ep->packet || !usb::is_in_endpoint(address) ||
      packet.size() > ep->config.max_packet)
    return false;
  ep->packet.emplace(packet.begin(), packet.end());
  return true;
}

void SimUsbController::receive(std::uint8_t address) {
  Endpoint* ep = find(address);
  if (ep != nullptr && ep->open && !usb::is_in_endpoint(address)) ep->armed = true;
}

void SimUsbController::answer(Ep0Answer answer) {
  ep0_answer_ = answer;
  ++ep0_answers_;
}

void SimUsbController::ep0_transmit(std::span<const std::uint8_t> data, bool zero_length_end) {
  ep0_zero_length_end_ = zero_length_end;
  ep0_in_.assign(data.begin(), data.end());
  ep0_in_view_ = data;
  answer(Ep0Answer::kTransmit);
}

void SimUsbController::ep0_receive(std::span<std::uint8_t> buffer) {
  ep0_out_buffer_ = buffer;
  answer(Ep0Answer::kReceive);
}

void SimUsbController::ep0_status() {
  answer(Ep0Answer::kStatus);
}

void SimUsbController::ep0_stall() {
  answer(Ep0Answer::kStall);
}

}  // namespace flutterscan::firmware::sim
