#pragma once
// The board's security floor (anti-rollback): the security_version of the
// newest image that confirmed itself (boot_decision.hpp, BootConfirmation).
// The bootloader starts no image below it, DFU mode manifests none, and it
// only ever rises: it is kept as a thermometer code in one-time-programmable
// cells, floor v = the first v bits (byte 0 bit 0 first) programmed to 0, so
// a power loss while it rises leaves the old floor or the new one (or one
// between), never a lower one.
// Freestanding C++20: no heap, no exceptions, no RTTI.

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

namespace flutterscan::firmware {

/// \brief Cells of the thermometer: 256 bits, floors 0..255.
inline constexpr std::size_t kSecurityFloorBytes = 32;

/// \brief The floor the cells hold: how many bits from the first are 0.
constexpr std::uint8_t security_floor_of(std::span<const std::uint8_t, kSecurityFloorBytes> cells) {
  unsigned floor = 0;
  for (const std::uint8_t byte : cells) {
    for (int bit = 0; bit < 8; ++bit) {
      if ((byte >> bit) & 1u) return static_cast<std::uint8_t>(floor);
      ++floor;
    }
  }
  return 255;  // every bit programmed: 256 saturates at the largest version
}

/// \brief The cells of floor `floor` (erased cells 0xFF, programmed bits 0).
constexpr std::array<std::uint8_t, kSecurityFloorBytes> security_floor_cells(std::uint8_t floor) {
  std::array<std::uint8_t, kSecurityFloorBytes> cells{};
  for (std::size_t i = 0; i < cells.size(); ++i) {
    const unsigned first = 8u * static_cast<unsigned>(i);
    const unsigned cleared = floor <= first ? 0u : (floor - first >= 8u ? 8u : floor - first);
    cells[i] = static_cast<std::uint8_t>(0xFFu << cleared);
  }
  return cells;
}

/// \brief Where the floor lives (OTP on the product, a cell array on the sim).
class SecurityFloor {
 public:
  /// \brief The floor now.
  virtual std::uint8_t floor() = 0;
  /// \brief Raises the floor to `version` if that is higher (never lowers it);
  /// false if the cells could not be programmed.
  virtual bool raise(std::uint8_t version) = 0;

 protected:
  ~SecurityFloor() = default;
};

}  // namespace flutterscan::firmware
