#pragma once
// One interface of the device (HID, DFU runtime, DFU mode) as the device core
// sees it: class requests addressed to the interface, its endpoints' traffic,
// and the device's state changes. Chapter 9 standard requests stay in UsbDevice.
// Freestanding C++20: no heap, no exceptions, no RTTI.

#include <cstddef>
#include <cstdint>
#include <span>

#include "flutterscan/firmware/usb/usb_device_controller.hpp"
#include "flutterscan/firmware/usb/usb_types.hpp"

namespace flutterscan::firmware::usb {

/// \brief How an interface answers a control request.
struct ControlReply {
  enum class Kind : std::uint8_t {
    kStall,        ///< refuse (nothing changed)
    kStatus,       ///< no data stage (or OUT data accepted): zero-length status
    kSendData,     ///< IN data stage: `length` bytes written into the EP0 buffer
    kReceiveData,  ///< OUT data stage of wLength bytes follows (control_out_data)
  };
  Kind kind = Kind::kStall;
  std::size_t length = 0;

  static constexpr ControlReply stall() { return {Kind::kStall, 0}; }
  static constexpr ControlReply status() { return {Kind::kStatus, 0}; }
  static constexpr ControlReply send(std::size_t n) { return {Kind::kSendData, n}; }
  static constexpr ControlReply receive() { return {Kind::kReceiveData, 0}; }
};

/// \brief A USB interface's class behaviour.
class UsbFunction {
 public:
  /// \brief A class request to this interface. `buffer` is the EP0 buffer
  /// (at least wLength bytes when wLength fits the buffer): write IN data there.
  virtual ControlReply control_request(const SetupPacket& setup,
                                       std::span<std::uint8_t> buffer) = 0;
  /// \brief The OUT data stage of a request answered with kReceiveData: kStatus or kStall.
  virtual ControlReply control_out_data(const SetupPacket& setup,
                                        std::span<const std::uint8_t> data) {
    (void)setup;
    (void)data;
    return ControlReply::stall();
  }
  /// \brief The control transfer `setup` (to this interface) has completed its status stage.
  virtual void control_complete(const SetupPacket& setup) { (void)setup; }

  /// \brief The device was configured (`configured`: its endpoints are open) or
  /// deconfigured (bus reset, SET_CONFIGURATION 0: endpoints closed).
  virtual void set_configured(bool configured) = 0;
  /// \brief The host reset the bus (after set_configured(false) when it was configured).
  virtual void bus_reset() {}
  /// \brief A packet on one of this interface's OUT endpoints.
  virtual void out_packet(std::uint8_t address, std::span<const std::uint8_t> packet) {
    (void)address;
    (void)packet;
  }
  /// \brief The host took the packet on one of this interface's IN endpoints.
  virtual void in_complete(std::uint8_t address) { (void)address; }
  /// \brief The host halted (`halted`) or un-halted one of this interface's
  /// endpoints (CLEAR_FEATURE and SET_INTERFACE un-halt even an endpoint that
  /// was not halted). Either way the controller dropped a packet queued on it
  /// and left an OUT endpoint un-armed.
  virtual void endpoint_halt_changed(std::uint8_t address, bool halted) {
    (void)address;
    (void)halted;
  }

 protected:
  ~UsbFunction() = default;
};

}  // namespace flutterscan::firmware::usb
