#pragma once
// The security floor (security_floor.hpp) in OTP block 0 of the STM32F405
// (kSecurityFloorAddress): read as memory, raised by programming words.

#include <cstdint>

#include "flutterscan/firmware/security_floor.hpp"

namespace flutterscan::firmware::stm32f4 {

/// \brief The floor in OTP: both images use it (the bootloader to refuse,
/// the application to raise it once it has confirmed itself).
class OtpSecurityFloor final : public SecurityFloor {
 public:
  std::uint8_t floor() override;
  bool raise(std::uint8_t version) override;
};

}  // namespace flutterscan::firmware::stm32f4
