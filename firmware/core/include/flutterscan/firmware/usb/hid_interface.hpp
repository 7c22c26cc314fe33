#pragma once
// The HID class interface of the application (interface 0): request reports
// from the interrupt OUT endpoint go to the CommandHandler; its replies and the
// controller's exposure events go out on the interrupt IN endpoint, replies
// first. A reply is never dropped: while the reply queue is full the OUT
// endpoint stays un-armed (the host's next request is NAKed until the host
// reads replies), and a reply the host halted in flight is sent again.
// Class requests: SET_IDLE and GET_IDLE are accepted; GET_REPORT, SET_REPORT
// and the boot protocol requests are answered with STALL (reports travel on
// the interrupt endpoints only).
//
// Context: out_packet(), in_complete() and poll() all run in the main loop
// (the drivers defer their interrupts), so CommandHandler and Controller calls
// happen there, never in interrupt context.
// Freestanding C++20: no heap, no exceptions, no RTTI.

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "flutterscan/common/protocol.hpp"
#include "flutterscan/firmware/command_handler.hpp"
#include "flutterscan/firmware/usb/usb_device_controller.hpp"
#include "flutterscan/firmware/usb/usb_function.hpp"

namespace flutterscan::firmware::usb {

/// Replies held until the host reads them.
inline constexpr std::size_t kHidReplyQueueCapacity = 4;

// HID 1.11 7.2 class requests.
inline constexpr std::uint8_t kHidGetReport = 0x01;
inline constexpr std::uint8_t kHidGetIdle = 0x02;
inline constexpr std::uint8_t kHidGetProtocol = 0x03;
inline constexpr std::uint8_t kHidSetReport = 0x09;
inline constexpr std::uint8_t kHidSetIdle = 0x0A;
inline constexpr std::uint8_t kHidSetProtocol = 0x0B;

/// \brief The command and event interface.
class HidInterface final : public UsbFunction {
 public:
  using Report = std::array<std::uint8_t, protocol::kReportSize>;

  /// \brief The interface on `controller`, answering through `handler`, on IN
  /// endpoint `in_address` and OUT endpoint `out_address`.
  HidInterface(UsbDeviceController& controller, CommandHandler& handler, std::uint8_t in_address,
               std::uint8_t out_address, std::uint8_t interface_number);

  /// \brief Main-loop work: handles a received request (if there is room for its
  /// reply), re-arms the OUT endpoint, and sends a reply or else an event when
  /// the IN endpoint is free.
  void poll();

  /// \brief Replies not yet taken by the host (queued or in flight).
  bool replies_pending() const { return reply_count_ != 0 || reply_in_flight_; }
  /// \brief A request received and not yet handled (its reply queue was full).
  bool request_pending() const { return request_size_ != 0; }
  std::uint8_t idle_rate() const { return idle_rate_; }

  // UsbFunction ------------------------------------------------------------
  ControlReply control_request(const SetupPacket& setup, std::span<std::uint8_t> buffer) override;
  void set_configured(bool configured) override;
  void bus_reset() override;
  void out_packet(std::uint8_t address, std::span<const std::uint8_t> packet) override;
  void in_complete(std::uint8_t address) override;
  void endpoint_halt_changed(std::uint8_t address, bool halted) override;

 private:
  /// Handles the received request if its reply fits; re-arms OUT.
  void handle_request();
  /// Starts the next IN transfer if the endpoint is free.
  void pump();
  void arm_out();

  UsbDeviceController& controller_;
  CommandHandler& handler_;
  std::uint8_t in_address_;
  std::uint8_t out_address_;
  std::uint8_t interface_number_;

  bool configured_ = false;
  bool in_busy_ = false;  ///< a packet is queued on IN and not yet taken
  bool in_halted_ = false;
  bool out_halted_ = false;
  bool out_armed_ = false;
  std::uint8_t idle_rate_ = 0;

  Report request_{};
  std::size_t request_size_ = 0;  ///< 0: none waiting
  bool request_zero_length_ = false;

  std::array<Report, kHidReplyQueueCapacity> replies_{};
  std::size_t reply_head_ = 0;
  std::size_t reply_count_ = 0;

  /// The packet on the IN endpoint (sent again if the host halts it in flight).
  Report in_flight_{};
  bool in_flight_valid_ = false;  ///< in_flight_ not yet taken by the host
  bool reply_in_flight_ = false;  ///< ... and it is a reply
  bool resend_in_flight_ = false;
};

}  // namespace flutterscan::firmware::usb
