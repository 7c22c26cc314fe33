#pragma once
// The thread-safe door from the umockdev handlers (which run on umockdev's
// worker thread) to the board (which the harness's service loop also drives).
// Every call names the enumeration it belongs to: once the board has
// re-enumerated (detach, manifest + reset, unplug) the old device node's calls
// fail with "gone" (ENODEV), as they do on Linux.

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "usb_board.hpp"

namespace flutterscan::hil {

/// \brief What happened to an interrupt OUT packet.
enum class OutResult { kTaken, kNak, kGone };

/// \brief Thread-safe access to one enumeration of the board.
class DevicePort {
 public:
  /// \brief Control transfer; nullopt if enumeration `generation` is gone.
  virtual std::optional<ControlOutcome> control(int generation,
                                                std::span<const std::uint8_t, 8> setup,
                                                std::span<const std::uint8_t> out_data) = 0;
  virtual OutResult interrupt_out(int generation, std::uint8_t address,
                                  std::span<const std::uint8_t> packet) = 0;
  /// \brief nullopt: gone; an empty optional inside: nothing waiting (NAK).
  virtual std::optional<std::optional<std::vector<std::uint8_t>>> interrupt_in(
      int generation, std::uint8_t address) = 0;
  /// \brief USBDEVFS_RESET; false if gone.
  virtual bool reset(int generation) = 0;
  /// \brief Whether enumeration `generation` is still on the bus.
  virtual bool present(int generation) = 0;

 protected:
  ~DevicePort() = default;
};

}  // namespace flutterscan::hil
