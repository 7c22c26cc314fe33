#pragma once
// SimUsbController: the UsbDeviceController seam in software, driven the way a
// USB host drives a device. A test or the HIL harness (which answers usbdevfs
// URBs for libusb and hidapi under umockdev) calls control_transfer(),
// interrupt_out(), interrupt_in() and bus_reset(); the controller turns each
// into the UsbDeviceEvents calls a hardware driver would make and returns what
// the device put on the wire. Everything is synchronous: a call returns when
// the transfer is over (status stage included). Host only.

#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <span>
#include <vector>

#include "flutterscan/firmware/usb/usb_device_controller.hpp"

namespace flutterscan::firmware::sim {

/// \brief What a control transfer ended with.
struct ControlResult {
  bool stalled = false;            ///< the device answered STALL (usbdevfs: EPIPE)
  std::vector<std::uint8_t> data;  ///< IN data stage (at most wLength bytes)
};

/// \brief What an interrupt OUT transaction ended with.
enum class OutResult : std::uint8_t {
  kAck,         ///< the device took the packet
  kNak,         ///< the device is busy (its reply queue is full): try again later
  kStall,       ///< the endpoint is halted (usbdevfs: EPIPE)
  kNoEndpoint,  ///< not configured, or no such OUT endpoint / packet too long
};

/// \brief A device controller played by the host side.
class SimUsbController final : public usb::UsbDeviceController {
 public:
  /// \brief Where the controller delivers events (the device core); nullptr: nowhere.
  void attach(usb::UsbDeviceEvents* device) { device_ = device; }

  // Host side -----------------------------------------------------------------
  /// \brief One control transfer: the 8 SETUP bytes, then the OUT data stage
  /// (`out_data`, wLength bytes, for host-to-device requests) or the IN data
  /// stage (returned), then the status stage.
  ControlResult control_transfer(std::span<const std::uint8_t, 8> setup,
                                 std::span<const std::uint8_t> out_data = {});
  /// \brief control_transfer() from fields.
  ControlResult control_transfer(std::uint8_t request_type, std::uint8_t request,
                                 std::uint16_t value, std::uint16_t index, std::uint16_t length,
                                 std::span<const std::uint8_t> out_data = {});
  /// \brief One packet to interrupt/bulk OUT endpoint `address`.
  OutResult interrupt_out(std::uint8_t address, std::span<const std::uint8_t> packet);
  /// \brief The packet waiting on IN endpoint `address` (the host ACKs it), or
  /// nothing (NAK; endpoint_halted() tells a STALL apart).
  std::optional<std::vector<std::uint8_t>> interrupt_in(std::uint8_t address);
  /// \brief USB bus reset: address 0, endpoints closed, then the device is told.
  void bus_reset();

  // Observations --------------------------------------------------------------
  std::uint8_t address() const { return address_; }
  bool endpoint_open(std::uint8_t address) const;
  bool endpoint_halted(std::uint8_t address) const;
  /// \brief A packet is waiting on IN endpoint `address`.
  bool in_packet_waiting(std::uint8_t address) const;
  /// \brief Control transfers the device answered in a way the seam forbids
  /// (no answer, two answers, wrong direction, a wrong zero-length-packet
  /// decision): should stay 0.
  int ep0_protocol_errors() const { return ep0_protocol_errors_; }

  // UsbDeviceController ---------------------------------------------------------
  void set_address(std::uint8_t address) override { address_ = address; }
  void open_endpoint(const usb::EndpointConfig& endpoint) override;
  void close_endpoint(std::uint8_t address) override;
  void set_stall(std::uint8_t address, bool stalled) override;
  bool transmit(std::uint8_t address, std::span<const std::uint8_t> packet) override;
  void receive(std::uint8_t address) override;
  void ep0_transmit(std::span<const std::uint8_t> data, bool zero_length_end) override;
  void ep0_receive(std::span<std::uint8_t> buffer) override;
  void ep0_status() override;
  void ep0_stall() override;

 private:
  struct Endpoint {
    usb::EndpointConfig config;
    bool open = false;
    bool halted = false;
    bool armed = false;                               ///< OUT: ready for one packet
    std::optional<std::vector<std::uint8_t>> packet;  ///< IN: queued packet
  };
  enum class Ep0Answer : std::uint8_t { kNone, kTransmit, kReceive, kStatus, kStall };

  void answer(Ep0Answer answer);
  Endpoint* find(std::uint8_t address);
  const Endpoint* find(std::uint8_t address) const;

  usb::UsbDeviceEvents* device_ = nullptr;
  std::uint8_t address_ = 0;
  std::map<std::uint8_t, Endpoint> endpoints_;

  Ep0Answer ep0_answer_ = Ep0Answer::kNone;
  int ep0_answers_ = 0;
  std::vector<std::uint8_t> ep0_in_;
  bool ep0_zero_length_end_ = false;
  std::span<std::uint8_t> ep0_out_buffer_;
  int ep0_protocol_errors_ = 0;
};

}  // namespace flutterscan::firmware::sim
