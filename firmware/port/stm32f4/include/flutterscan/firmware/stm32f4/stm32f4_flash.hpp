#pragma once
// The bootloader's Flash seam on the STM32F405: sector erase and x32
// programming through the flash interface (system.hpp: flash_erase_sector,
// flash_program, which refuse sector 0 themselves), reads from the
// memory-mapped flash.

#include <cstddef>
#include <cstdint>
#include <span>

#include "flutterscan/firmware/flash.hpp"

namespace flutterscan::firmware::stm32f4 {

/// \brief On-chip flash.
class Stm32f4Flash final : public Flash {
 public:
  FlashResult erase_sector(int sector) override;
  FlashResult program(std::uint32_t address, std::span<const std::uint8_t> data) override;
  std::span<const std::uint8_t> read(std::uint32_t address, std::size_t size) override;
};

/// \brief The chip's 96-bit unique ID (RM0090 39.1), byte 0 first.
std::span<const std::uint8_t, 12> unique_id();

}  // namespace flutterscan::firmware::stm32f4
