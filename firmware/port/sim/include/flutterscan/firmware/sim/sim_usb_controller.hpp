#pragma once
// SimUsbController: the UsbDeviceController seam in software, driven the way a
// USB host drives a device. A test or the HIL harness (which answers usbdevfs
// URBs for libusb and hidapi under umockdev) calls control_transfer(),
// interrupt_out(), interrupt_in() and bus_reset(); the controller turns each
// into the UsbDeviceEvents calls a hardware driver would make and returns what
// the device put on the wire. control_transfer() is synchronous: it returns
// when the transfer is over (status stage included); the packet-level path
// (setup_packet(), ep0_in_packet(), ep0_out_packet()) plays one endpoint-0
// transaction per call. Host only.

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

/// \brief The handshake of one endpoint-0 transaction of the packet-level path.
enum class Ep0Handshake : std::uint8_t {
  kAck,    ///< the packet was taken (OUT) or sent (IN)
  kNak,    ///< nothing to send / not ready for it (no stage of the transfer expects it)
  kStall,  ///< the control transfer was answered with STALL (until the next SETUP)
};

/// \brief What an IN transaction on endpoint 0 returned.
struct Ep0InPacket {
  Ep0Handshake handshake = Ep0Handshake::kNak;
  std::vector<std::uint8_t> data;  ///< kAck: the packet (0..64 bytes)
};

/// \brief Where the packet-level control transfer is.
enum class Ep0Stage : std::uint8_t {
  kIdle,       ///< no transfer (or the last one completed)
  kInData,     ///< IN data stage: the host reads packets, then sends the OUT status packet
  kOutData,    ///< OUT data stage: the host sends packets of up to 64 bytes
  kStatusIn,   ///< the device's zero-length IN status packet is ready
  kStatusOut,  ///< IN data all sent: the host's zero-length OUT status packet is due
  kStalled,    ///< STALL until the next SETUP
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

  // Host side, packet level -----------------------------------------------------
  // Endpoint 0 one transaction at a time, as the OTG_FS driver sees a control
  // transfer (port/stm32f4/src/otg_fs_device.cpp; sim_usb_ep0_packets.cpp): the
  // IN data stage is read from the core's buffer 64 bytes per packet (a zero-
  // length packet where the seam asked for one), the OUT data stage is taken
  // into the core's buffer packet by packet and reported when it is full or a
  // packet shorter than 64 bytes ends it, then the status stage. A SETUP is
  // always taken and aborts whatever transfer was in progress (USB 2.0 8.5.3).
  /// \brief A SETUP packet.
  void setup_packet(std::span<const std::uint8_t, 8> setup);
  /// \brief An IN transaction on endpoint 0: a data-stage packet, or the zero-
  /// length status packet (the transfer completes), or NAK or STALL.
  Ep0InPacket ep0_in_packet();
  /// \brief An OUT transaction on endpoint 0 (at most 64 bytes, else STALL
  /// and nothing delivered): a data-stage packet, or the zero-length status
  /// packet after an IN data stage (the transfer completes; also early, before
  /// the last IN packet, as a host may).
  Ep0Handshake ep0_out_packet(std::span<const std::uint8_t> packet);
  Ep0Stage ep0_stage() const { return ep0_stage_; }
  /// \brief Control transfers whose status stage completed on the packet path.
  int ep0_transfers_completed() const { return ep0_completed_; }

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
  /// The packet path after the device answered a SETUP or an OUT data stage.
  void enter_stage_after_answer();
  void complete_status_stage();
  Endpoint* find(std::uint8_t address);
  const Endpoint* find(std::uint8_t address) const;

  usb::UsbDeviceEvents* device_ = nullptr;
  std::uint8_t address_ = 0;
  std::map<std::uint8_t, Endpoint> endpoints_;

  Ep0Answer ep0_answer_ = Ep0Answer::kNone;
  int ep0_answers_ = 0;
  std::vector<std::uint8_t> ep0_in_;
  std::span<const std::uint8_t> ep0_in_view_;  ///< the core's buffer, read packet by packet
  bool ep0_zero_length_end_ = false;
  std::span<std::uint8_t> ep0_out_buffer_;
  int ep0_protocol_errors_ = 0;

  // Packet path.
  Ep0Stage ep0_stage_ = Ep0Stage::kIdle;
  bool ep0_setup_in_ = false;             ///< the SETUP's direction
  std::uint16_t ep0_setup_length_ = 0;    ///< its wLength
  std::size_t ep0_in_sent_ = 0;           ///< IN data bytes sent in this data stage
  bool ep0_zero_length_pending_ = false;  ///< a zero-length packet still ends the IN stage
  std::size_t ep0_out_received_ = 0;      ///< OUT data bytes taken in this data stage
  int ep0_completed_ = 0;
};

}  // namespace flutterscan::firmware::sim
