#include "flutterscan/firmware/stm32f4/otp_security_floor.hpp"

#include <array>
#include <cstring>
#include <span>

#include "flutterscan/firmware/stm32f4/stm32f4_board.hpp"
#include "flutterscan/firmware/stm32f4/system.hpp"

namespace flutterscan::firmware::stm32f4 {

namespace {

std::span<const std::uint8_t, kSecurityFloorBytes> otp_cells() {
  return std::span<const std::uint8_t, kSecurityFloorBytes>(
      reinterpret_cast<const std::uint8_t*>(static_cast<std::uintptr_t>(kSecurityFloorAddress)),
      kSecurityFloorBytes);
}

}  // namespace

std::uint8_t OtpSecurityFloor::floor() {
  return security_floor_of(otp_cells());
}

bool OtpSecurityFloor::raise(std::uint8_t version) {
  if (version <= floor()) return true;
  // Each word whose bits change: programmed once with the bits it keeps
  // (thermometer: only 1 -> 0, so words already right are left alone).
  const auto target = security_floor_cells(version);
  const auto cells = otp_cells();
  for (std::size_t w = 0; w < kSecurityFloorBytes / 4; ++w) {
    std::uint32_t now = 0;
    std::uint32_t want = 0;
    std::memcpy(&now, cells.data() + 4 * w, 4);
    std::memcpy(&want, target.data() + 4 * w, 4);
    if ((now & want) == now) continue;
    const std::array<std::uint32_t, 1> word{now & want};
    if (otp_program(kSecurityFloorAddress + 4 * static_cast<std::uint32_t>(w), word) !=
        PortStatus::kOk)
      return false;
  }
  return floor() == version;
}

}  // namespace flutterscan::firmware::stm32f4
