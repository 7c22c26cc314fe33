#pragma once
// The USB device-controller seam: what a hardware driver (port/stm32f4's OTG FS
// driver) or a simulation (port/sim's SimUsbController) provides to the
// hardware-independent device core (UsbDevice), and, in UsbDeviceEvents, the
// entry points the driver calls into the core.
//
// Threading: the core is not reentrant. A driver calls the UsbDeviceEvents
// functions from one context (the STM32F4 driver from the main loop, having
// deferred its interrupt), and the core calls the controller from inside
// those calls or from its own poll() in that same context.
//
// Control transfers on endpoint 0 (USB 2.0 8.5.3): the driver reports each
// SETUP with on_setup(). Inside it (or, for an OUT data stage, inside
// on_ep0_out_complete()) the core answers with exactly one of ep0_transmit()
// (IN data stage; the driver then completes the OUT status stage itself),
// ep0_receive() (OUT data stage; the driver reports it with
// on_ep0_out_complete()), ep0_status() (zero-length IN status stage) or
// ep0_stall(). When the status stage has been acknowledged by the host the
// driver calls on_ep0_status_complete(). A new SETUP always aborts whatever
// control transfer was in progress.
// Freestanding C++20: no heap, no exceptions, no RTTI.

#include <cstddef>
#include <cstdint>
#include <span>

#include "flutterscan/firmware/usb/usb_types.hpp"

namespace flutterscan::firmware::usb {

/// \brief What a device-controller driver does for the device core.
class UsbDeviceController {
 public:
  /// \brief The host assigned `address` (SET_ADDRESS, called from on_setup before
  /// the status stage). A controller that must apply the address only after the
  /// status stage (USB 2.0 9.4.6) defers it itself; the OTG FS core takes it at once.
  virtual void set_address(std::uint8_t address) = 0;

  /// \brief Opens a non-control endpoint (SET_CONFIGURATION), DATA0, not stalled,
  /// an OUT endpoint not yet armed (receive() arms it).
  virtual void open_endpoint(const EndpointConfig& endpoint) = 0;
  /// \brief Closes a non-control endpoint, dropping a packet waiting in it.
  virtual void close_endpoint(std::uint8_t address) = 0;
  /// \brief Halts (`stalled`) or un-halts a non-control endpoint; un-halting
  /// resets its data toggle to DATA0 (USB 2.0 9.4.5) and drops a packet queued on it.
  virtual void set_stall(std::uint8_t address, bool stalled) = 0;

  /// \brief Queues one packet (at most the endpoint's max packet size) on IN
  /// endpoint `address`; the data are copied before this returns. False if the
  /// endpoint is busy with an unacknowledged packet, closed or halted.
  /// on_in_complete() follows when the host has taken it.
  virtual bool transmit(std::uint8_t address, std::span<const std::uint8_t> packet) = 0;
  /// \brief Arms OUT endpoint `address` for one packet (NAK until then);
  /// on_out_packet() reports it, after which the endpoint NAKs again.
  virtual void receive(std::uint8_t address) = 0;

  /// \brief Endpoint 0 IN data stage: sends `data` in max-packet pieces, then a
  /// zero-length packet if `zero_length_end` (data shorter than wLength and a
  /// multiple of the packet size). `data` stays valid until the transfer ends.
  virtual void ep0_transmit(std::span<const std::uint8_t> data, bool zero_length_end) = 0;
  /// \brief Endpoint 0 OUT data stage: receives buffer.size() bytes into `buffer`
  /// (valid until on_ep0_out_complete()).
  virtual void ep0_receive(std::span<std::uint8_t> buffer) = 0;
  /// \brief Endpoint 0 status stage: a zero-length IN packet.
  virtual void ep0_status() = 0;
  /// \brief Endpoint 0 answers the current control transfer with STALL (until the next SETUP).
  virtual void ep0_stall() = 0;

 protected:
  ~UsbDeviceController() = default;
};

/// \brief The device core's entry points a driver calls.
class UsbDeviceEvents {
 public:
  /// \brief The host reset the bus: address 0, unconfigured, endpoints closed.
  virtual void on_bus_reset() = 0;
  /// \brief A SETUP packet arrived on endpoint 0.
  virtual void on_setup(const SetupPacket& setup) = 0;
  /// \brief The OUT data stage requested by ep0_receive() is complete (`received` bytes).
  virtual void on_ep0_out_complete(std::size_t received) = 0;
  /// \brief The host acknowledged the status stage: the control transfer is done.
  virtual void on_ep0_status_complete() = 0;
  /// \brief A packet arrived on armed OUT endpoint `address`.
  virtual void on_out_packet(std::uint8_t address, std::span<const std::uint8_t> packet) = 0;
  /// \brief The host took the packet queued on IN endpoint `address`.
  virtual void on_in_complete(std::uint8_t address) = 0;

 protected:
  ~UsbDeviceEvents() = default;
};

}  // namespace flutterscan::firmware::usb
