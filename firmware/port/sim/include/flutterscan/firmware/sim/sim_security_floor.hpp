#pragma once
// The security floor (security_floor.hpp) in simulated one-time-programmable
// cells: programming only clears bits, nothing erases them, and they survive
// every reset and power cycle of the SimBoard that owns them.

#include <array>
#include <cstdint>

#include "flutterscan/firmware/security_floor.hpp"

namespace flutterscan::firmware::sim {

/// \brief A security floor in 32 cells that only programming (1 -> 0) changes.
class SimSecurityFloor final : public SecurityFloor {
 public:
  std::uint8_t floor() override { return security_floor_of(cells_); }
  bool raise(std::uint8_t version) override {
    if (version <= floor()) return true;
    const auto target = security_floor_cells(version);
    for (std::size_t i = 0; i < cells_.size(); ++i)
      cells_[i] = static_cast<std::uint8_t>(cells_[i] & target[i]);
    return floor() == version;
  }
  /// \brief The cells as they are (tests).
  const std::array<std::uint8_t, kSecurityFloorBytes>& cells() const { return cells_; }

 private:
  std::array<std::uint8_t, kSecurityFloorBytes> cells_ = security_floor_cells(0);
};

}  // namespace flutterscan::firmware::sim
