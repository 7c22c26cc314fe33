#pragma once
// What the umockdev layer of the HIL harness needs from the board it serves:
// the bus side of a USB device, the way usbdevfs sees one (control transfers
// on endpoint 0, interrupt packets on the other endpoints, bus reset). The
// harness's BoardHost implements it on the firmware's own USB core running on
// port/sim; the usbdevfs and hidraw emulations only ever talk to this.
// Not thread-safe: the caller serialises (BoardHost holds one lock).

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "flutterscan/firmware/usb/usb_types.hpp"

namespace flutterscan::hil {

/// \brief How a control transfer ended.
struct ControlOutcome {
  bool stalled = false;
  std::vector<std::uint8_t> in_data;  ///< IN data stage (empty for OUT transfers)
};

/// \brief The device as the bus sees it.
class UsbBoard {
 public:
  virtual ~UsbBoard() = default;
  /// \brief One control transfer: SETUP, data stage (`out_data` for OUT requests,
  /// at most wLength IN bytes returned), status stage.
  virtual ControlOutcome control_transfer(std::span<const std::uint8_t, 8> setup,
                                          std::span<const std::uint8_t> out_data) = 0;
  /// \brief One packet to OUT endpoint `address`; false while the endpoint NAKs
  /// (the packet is not taken: send it again later).
  virtual bool interrupt_out(std::uint8_t address, std::span<const std::uint8_t> packet) = 0;
  /// \brief The packet waiting on IN endpoint `address`, if any (taking it acknowledges it).
  virtual std::optional<std::vector<std::uint8_t>> interrupt_in(std::uint8_t address) = 0;
  /// \brief A USB bus reset.
  virtual void bus_reset() = 0;
};

/// \brief Builds a SETUP packet.
constexpr std::array<std::uint8_t, 8> make_setup(std::uint8_t request_type, std::uint8_t request,
                                                 std::uint16_t value, std::uint16_t index,
                                                 std::uint16_t length) {
  return firmware::usb::SetupPacket{request_type, request, value, index, length}.bytes();
}

}  // namespace flutterscan::hil
