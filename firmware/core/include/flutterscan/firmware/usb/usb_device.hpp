#pragma once
// The hardware-independent USB device core: chapter 9 of USB 2.0 on top of a
// UsbDeviceController. It answers the standard requests (GET_DESCRIPTOR of the
// device, configuration, string and HID descriptors, SET_ADDRESS,
// SET/GET_CONFIGURATION, GET_STATUS, CLEAR/SET_FEATURE(ENDPOINT_HALT),
// GET/SET_INTERFACE) from a UsbDescriptorSet, opens and closes the endpoints,
// and passes class requests and endpoint traffic to the interfaces
// (UsbFunction). A request that is unknown, malformed, or not allowed in the
// device's state is answered with STALL and changes nothing.
// Freestanding C++20: no heap, no exceptions, no RTTI.

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "flutterscan/firmware/usb/usb_descriptors.hpp"
#include "flutterscan/firmware/usb/usb_device_controller.hpp"
#include "flutterscan/firmware/usb/usb_function.hpp"
#include "flutterscan/firmware/usb/usb_types.hpp"

namespace flutterscan::firmware::usb {

/// Bytes of the EP0 data buffer: the longest data stage (a 1024-byte DFU block).
inline constexpr std::size_t kEp0BufferSize = 1024;
/// Interfaces a device may have.
inline constexpr std::size_t kMaxInterfaces = 4;

/// \brief USB 2.0 9.1 device states the core distinguishes.
enum class DeviceState : std::uint8_t { kDefault, kAddress, kConfigured };

/// \brief The device core.
class UsbDevice final : public UsbDeviceEvents {
 public:
  /// \brief A device on `controller` serving `descriptors` (which, like the
  /// controller, must outlive it), with the serial number made from `unique_id`.
  UsbDevice(UsbDeviceController& controller, const UsbDescriptorSet& descriptors,
            std::span<const std::uint8_t, kUniqueIdSize> unique_id);
  UsbDevice(const UsbDevice&) = delete;
  UsbDevice& operator=(const UsbDevice&) = delete;

  /// \brief Installs the class behaviour of interface `number` (< interface_count).
  void set_function(std::uint8_t number, UsbFunction* function);

  // UsbDeviceEvents ----------------------------------------------------------
  void on_bus_reset() override;
  void on_setup(const SetupPacket& setup) override;
  void on_ep0_out_complete(std::size_t received) override;
  void on_ep0_status_complete() override;
  void on_out_packet(std::uint8_t address, std::span<const std::uint8_t> packet) override;
  void on_in_complete(std::uint8_t address) override;

  DeviceState state() const { return state_; }
  std::uint8_t address() const { return address_; }
  std::uint8_t configuration() const { return configuration_; }
  bool configured() const { return state_ == DeviceState::kConfigured; }
  /// \brief Whether the host halted non-control endpoint `address`.
  bool endpoint_halted(std::uint8_t address) const;
  /// \brief The serial number string descriptor served for string index serial_index.
  std::span<const std::uint8_t> serial_descriptor() const { return serial_descriptor_; }

 private:
  /// Who finishes the current control transfer.
  enum class Ep0Owner : std::uint8_t { kNone, kStandard, kFunction };

  ControlReply standard_request(const SetupPacket& setup);
  ControlReply get_descriptor(const SetupPacket& setup);
  ControlReply get_status(const SetupPacket& setup);
  ControlReply endpoint_feature(const SetupPacket& setup, bool set);
  ControlReply set_configuration(const SetupPacket& setup);
  ControlReply interface_request(const SetupPacket& setup);
  /// Answers the current control transfer as `reply` says.
  void finish_setup(const SetupPacket& setup, ControlReply reply);
  /// Copies `bytes` into the EP0 buffer: a kSendData reply.
  ControlReply send(std::span<const std::uint8_t> bytes);

  const EndpointConfig* find_endpoint(std::uint8_t address) const;
  UsbFunction* function_of_endpoint(std::uint8_t address) const;
  UsbFunction* function_for_interface(std::uint16_t index) const;
  void open_endpoints();
  void close_endpoints();
  void set_halt_flag(std::uint8_t address, bool halted);

  UsbDeviceController& controller_;
  const UsbDescriptorSet& descriptors_;
  std::array<std::uint8_t, 2 + 2 * kSerialLength> serial_descriptor_;
  std::array<UsbFunction*, kMaxInterfaces> functions_{};

  DeviceState state_ = DeviceState::kDefault;
  std::uint8_t address_ = 0;
  std::uint8_t configuration_ = 0;
  std::uint32_t halted_ = 0;  ///< bit n: OUT endpoint n; bit 16 + n: IN endpoint n

  SetupPacket setup_;
  Ep0Owner ep0_owner_ = Ep0Owner::kNone;
  UsbFunction* ep0_function_ = nullptr;
  std::array<std::uint8_t, kEp0BufferSize> ep0_buffer_{};
};

}  // namespace flutterscan::firmware::usb
