#include "flutterscan/firmware/usb/usb_device.hpp"

#include <algorithm>

namespace flutterscan::firmware::usb {

namespace {

std::uint32_t halt_bit(std::uint8_t address) {
  return 1u << (endpoint_number(address) + (is_in_endpoint(address) ? 16 : 0));
}

/// Standard request with no data stage: wLength must be 0 and the direction OUT.
bool no_data(const SetupPacket& setup) {
  return setup.length == 0 && !setup.is_in();
}

}  // namespace

UsbDevice::UsbDevice(UsbDeviceController& controller, const UsbDescriptorSet& descriptors,
                     std::span<const std::uint8_t, kUniqueIdSize> unique_id)
    : controller_(controller),
      descriptors_(descriptors),
      serial_descriptor_(serial_string_descriptor(unique_id)) {}

void UsbDevice::set_function(std::uint8_t number, UsbFunction* function) {
  if (number < kMaxInterfaces && number < descriptors_.interface_count)
    functions_[number] = function;
}

bool UsbDevice::endpoint_halted(std::uint8_t address) const {
  return (halted_ & halt_bit(address)) != 0;
}

// ---------------------------------------------------------------------------
// Bus events

void UsbDevice::on_bus_reset() {
  if (state_ == DeviceState::kConfigured) {
    for (UsbFunction* f : functions_)
      if (f != nullptr) f->set_configured(false);
    close_endpoints();
  }
  state_ = DeviceState::kDefault;
  address_ = 0;
  configuration_ = 0;
  halted_ = 0;
  ep0_owner_ = Ep0Owner::kNone;
  ep0_function_ = nullptr;
  for (UsbFunction* f : functions_)
    if (f != nullptr) f->bus_reset();
}

void UsbDevice::on_setup(const SetupPacket& setup) {
  setup_ = setup;
  ep0_owner_ = Ep0Owner::kNone;
  ep0_function_ = nullptr;
  ControlReply reply = ControlReply::stall();
  switch (setup.type()) {
    case kRequestTypeStandard:
      reply = standard_request(setup);
      if (reply.kind != ControlReply::Kind::kStall) ep0_owner_ = Ep0Owner::kStandard;
      break;
    case kRequestTypeClass:
      if (setup.recipient() == kRecipientInterface && state_ == DeviceState::kConfigured) {
        UsbFunction* f = function_for_interface(setup.index);
        if (f != nullptr) {
          reply = f->control_request(setup, ep0_buffer_);
          if (reply.kind != ControlReply::Kind::kStall) {
            ep0_owner_ = Ep0Owner::kFunction;
            ep0_function_ = f;
          }
        }
      }
      break;
    default:
      break;  // vendor and reserved types: stall
  }
  finish_setup(setup, reply);
}

void UsbDevice::finish_setup(const SetupPacket& setup, ControlReply reply) {
  switch (reply.kind) {
    case ControlReply::Kind::kStall:
      ep0_owner_ = Ep0Owner::kNone;
      controller_.ep0_stall();
      return;
    case ControlReply::Kind::kStatus:
      if (setup.is_in() && setup.length > 0) {
        // An IN request answered without data: a zero-length data stage.
        controller_.ep0_transmit({}, true);
      } else {
        controller_.ep0_status();
      }
      return;
    case ControlReply::Kind::kSendData: {
      if (!setup.is_in()) {
        ep0_owner_ = Ep0Owner::kNone;
        controller_.ep0_stall();
        return;
      }
      const std::size_t n = std::min<std::size_t>(
          {reply.length, static_cast<std::size_t>(setup.length), ep0_buffer_.size()});
      const bool zlp = n < setup.length && n % kEp0MaxPacket == 0;
      controller_.ep0_transmit(std::span<const std::uint8_t>(ep0_buffer_).first(n), zlp);
      return;
    }
    case ControlReply::Kind::kReceiveData:
      if (setup.is_in() || setup.length == 0 || setup.length > ep0_buffer_.size()) {
        ep0_owner_ = Ep0Owner::kNone;
        controller_.ep0_stall();
        return;
      }
      controller_.ep0_receive(std::span<std::uint8_t>(ep0_buffer_).first(setup.length));
      return;
  }
}

void UsbDevice::on_ep0_out_complete(std::size_t received) {
  if (ep0_owner_ != Ep0Owner::kFunction || ep0_function_ == nullptr || received != setup_.length) {
    ep0_owner_ = Ep0Owner::kNone;
    controller_.ep0_stall();
    return;
  }
  const ControlReply reply = ep0_function_->control_out_data(
      setup_, std::span<const std::uint8_t>(ep0_buffer_).first(received));
  if (reply.kind == ControlReply::Kind::kStatus) {
    controller_.ep0_status();
  } else {
    ep0_owner_ = Ep0Owner::kNone;
    controller_.ep0_stall();
  }
}

void UsbDevice::on_ep0_status_complete() {
  const Ep0Owner owner = ep0_owner_;
  UsbFunction* f = ep0_function_;
  ep0_owner_ = Ep0Owner::kNone;
  ep0_function_ = nullptr;
  if (owner == Ep0Owner::kFunction && f != nullptr) f->control_complete(setup_);
}

void UsbDevice::on_out_packet(std::uint8_t address, std::span<const std::uint8_t> packet) {
  if (state_ != DeviceState::kConfigured) return;
  if (UsbFunction* f = function_of_endpoint(address)) f->out_packet(address, packet);
}

void UsbDevice::on_in_complete(std::uint8_t address) {
  if (state_ != DeviceState::kConfigured) return;
  if (UsbFunction* f = function_of_endpoint(address)) f->in_complete(address);
}

// ---------------------------------------------------------------------------
// Standard requests (USB 2.0 9.4)

ControlReply UsbDevice::send(std::span<const std::uint8_t> bytes) {
  const std::size_t n = std::min(bytes.size(), ep0_buffer_.size());
  std::copy_n(bytes.begin(), n, ep0_buffer_.begin());
  return ControlReply::send(n);
}

ControlReply UsbDevice::standard_request(const SetupPacket& setup) {
  switch (static_cast<StandardRequest>(setup.request)) {
    case StandardRequest::kGetStatus:
      return get_status(setup);
    case StandardRequest::kClearFeature:
      return endpoint_feature(setup, false);
    case StandardRequest::kSetFeature:
      return endpoint_feature(setup, true);
    case StandardRequest::kSetAddress:
      if (setup.request_type != 0x00 || !no_data(setup) || setup.value > 127 || setup.index != 0 ||
          state_ == DeviceState::kConfigured)
        return ControlReply::stall();
      address_ = static_cast<std::uint8_t>(setup.value);
      state_ = address_ == 0 ? DeviceState::kDefault : DeviceState::kAddress;
      controller_.set_address(address_);
      return ControlReply::status();
    case StandardRequest::kGetDescriptor:
      return get_descriptor(setup);
    case StandardRequest::kGetConfiguration:
      if (setup.request_type != 0x80 || setup.value != 0 || setup.index != 0 || setup.length == 0 ||
          state_ == DeviceState::kDefault)
        return ControlReply::stall();
      ep0_buffer_[0] = configuration_;
      return ControlReply::send(1);
    case StandardRequest::kSetConfiguration:
      return set_configuration(setup);
    case StandardRequest::kGetInterface:
    case StandardRequest::kSetInterface:
      return interface_request(setup);
    case StandardRequest::kSetDescriptor:
    case StandardRequest::kSynchFrame:
      break;
  }
  return ControlReply::stall();
}

ControlReply UsbDevice::get_descriptor(const SetupPacket& setup) {
  if (!setup.is_in() || setup.length == 0) return ControlReply::stall();
  const auto type = static_cast<DescriptorType>(setup.value >> 8);
  const std::uint8_t index = static_cast<std::uint8_t>(setup.value & 0xFF);
  if (setup.recipient() == kRecipientDevice) {
    switch (type) {
      case DescriptorType::kDevice:
        if (index != 0 || setup.index != 0) return ControlReply::stall();
        return send(descriptors_.device);
      case DescriptorType::kConfiguration:
        if (index != 0 || setup.index != 0) return ControlReply::stall();
        return send(descriptors_.configuration);
      case DescriptorType::kString:
        if (index == descriptors_.serial_index && index != 0) return send(serial_descriptor_);
        if (index >= descriptors_.strings.size() || descriptors_.strings[index].empty())
          return ControlReply::stall();
        return send(descriptors_.strings[index]);
      default:
        return ControlReply::stall();  // device qualifier and others: full-speed only device
    }
  }
  if (setup.recipient() == kRecipientInterface && state_ == DeviceState::kConfigured &&
      !descriptors_.hid_report_descriptor.empty() && setup.index == descriptors_.hid_interface) {
    if (type == DescriptorType::kHid && index == 0) return send(descriptors_.hid_descriptor);
    if (type == DescriptorType::kHidReport && index == 0)
      return send(descriptors_.hid_report_descriptor);
  }
  return ControlReply::stall();
}

ControlReply UsbDevice::get_status(const SetupPacket& setup) {
  if (!setup.is_in() || setup.value != 0 || setup.length != 2 || state_ == DeviceState::kDefault)
    return ControlReply::stall();
  ep0_buffer_[0] = 0;
  ep0_buffer_[1] = 0;
  switch (setup.recipient()) {
    case kRecipientDevice:
      if (setup.index != 0) return ControlReply::stall();
      return ControlReply::send(2);  // bus powered, no remote wakeup
    case kRecipientInterface:
      if (state_ != DeviceState::kConfigured || setup.index >= descriptors_.interface_count)
        return ControlReply::stall();
      return ControlReply::send(2);
    case kRecipientEndpoint: {
      const auto address = static_cast<std::uint8_t>(setup.index & 0xFF);
      if ((setup.index & 0xFF00) != 0) return ControlReply::stall();
      if (endpoint_number(address) == 0) {
        if ((address & 0x70) != 0) return ControlReply::stall();
        return ControlReply::send(2);
      }
      if (state_ != DeviceState::kConfigured || find_endpoint(address) == nullptr)
        return ControlReply::stall();
      ep0_buffer_[0] = endpoint_halted(address) ? 1 : 0;
      return ControlReply::send(2);
    }
    default:
      return ControlReply::stall();
  }
}

ControlReply UsbDevice::endpoint_feature(const SetupPacket& setup, bool set) {
  // Only ENDPOINT_HALT is supported: no remote wakeup (bmAttributes says so),
  // no test modes (full speed).
  if (!no_data(setup) || setup.recipient() != kRecipientEndpoint ||
      setup.value != kFeatureEndpointHalt || (setup.index & 0xFF00) != 0 ||
      state_ == DeviceState::kDefault)
    return ControlReply::stall();
  const auto address = static_cast<std::uint8_t>(setup.index & 0xFF);
  if (endpoint_number(address) == 0) {
    if ((address & 0x70) != 0 || set) return ControlReply::stall();
    return ControlReply::status();  // clearing EP0's halt: nothing to clear
  }
  if (state_ != DeviceState::kConfigured || find_endpoint(address) == nullptr)
    return ControlReply::stall();
  controller_.set_stall(address, set);
  set_halt_flag(address, set);
  if (UsbFunction* f = function_of_endpoint(address)) f->endpoint_halt_changed(address, set);
  return ControlReply::status();
}

ControlReply UsbDevice::set_configuration(const SetupPacket& setup) {
  if (setup.request_type != 0x00 || !no_data(setup) || setup.index != 0 ||
      (setup.value >> 8) != 0 || state_ == DeviceState::kDefault)
    return ControlReply::stall();
  const auto value = static_cast<std::uint8_t>(setup.value);
  if (value != 0 && value != descriptors_.configuration_value) return ControlReply::stall();
  if (state_ == DeviceState::kConfigured) {
    for (UsbFunction* f : functions_)
      if (f != nullptr) f->set_configured(false);
    close_endpoints();
  }
  halted_ = 0;
  configuration_ = value;
  if (value == 0) {
    state_ = DeviceState::kAddress;
    return ControlReply::status();
  }
  state_ = DeviceState::kConfigured;
  open_endpoints();
  for (UsbFunction* f : functions_)
    if (f != nullptr) f->set_configured(true);
  return ControlReply::status();
}

ControlReply UsbDevice::interface_request(const SetupPacket& setup) {
  if (setup.recipient() != kRecipientInterface || state_ != DeviceState::kConfigured ||
      setup.index >= descriptors_.interface_count)
    return ControlReply::stall();
  if (setup.request == static_cast<std::uint8_t>(StandardRequest::kGetInterface)) {
    if (!setup.is_in() || setup.value != 0 || setup.length != 1) return ControlReply::stall();
    ep0_buffer_[0] = 0;  // every interface has only alternate setting 0
    return ControlReply::send(1);
  }
  // SET_INTERFACE: only alternate setting 0 exists; selecting it resets the
  // interface's endpoints (halt cleared, DATA0).
  if (!no_data(setup) || setup.value != 0) return ControlReply::stall();
  for (const EndpointConfig& ep : descriptors_.endpoints) {
    if (ep.interface != setup.index) continue;
    controller_.set_stall(ep.address, false);  // drops a queued packet, OUT left un-armed
    set_halt_flag(ep.address, false);
    if (UsbFunction* f = function_of_endpoint(ep.address))
      f->endpoint_halt_changed(ep.address, false);
  }
  return ControlReply::status();
}

// ---------------------------------------------------------------------------
// Endpoints

const EndpointConfig* UsbDevice::find_endpoint(std::uint8_t address) const {
  for (const EndpointConfig& ep : descriptors_.endpoints)
    if (ep.address == address) return &ep;
  return nullptr;
}

UsbFunction* UsbDevice::function_of_endpoint(std::uint8_t address) const {
  const EndpointConfig* ep = find_endpoint(address);
  if (ep == nullptr || ep->interface >= kMaxInterfaces) return nullptr;
  return functions_[ep->interface];
}

UsbFunction* UsbDevice::function_for_interface(std::uint16_t index) const {
  if (index >= descriptors_.interface_count || index >= kMaxInterfaces) return nullptr;
  return functions_[index];
}

void UsbDevice::open_endpoints() {
  for (const EndpointConfig& ep : descriptors_.endpoints) controller_.open_endpoint(ep);
}

void UsbDevice::close_endpoints() {
  for (const EndpointConfig& ep : descriptors_.endpoints) controller_.close_endpoint(ep.address);
}

void UsbDevice::set_halt_flag(std::uint8_t address, bool halted) {
  if (halted)
    halted_ |= halt_bit(address);
  else
    halted_ &= ~halt_bit(address);
}

}  // namespace flutterscan::firmware::usb
