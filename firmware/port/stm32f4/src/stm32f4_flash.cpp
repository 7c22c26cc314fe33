#include "flutterscan/firmware/stm32f4/stm32f4_flash.hpp"

#include "flutterscan/firmware/stm32f4/registers.hpp"
#include "flutterscan/firmware/stm32f4/stm32f4_board.hpp"
#include "flutterscan/firmware/stm32f4/system.hpp"

namespace flutterscan::firmware::stm32f4 {

FlashResult Stm32f4Flash::erase_sector(int sector) {
  return flash_erase_sector(sector) == PortStatus::kOk ? FlashResult::kOk
                                                       : FlashResult::kEraseFailed;
}

FlashResult Stm32f4Flash::program(std::uint32_t address, std::span<const std::uint8_t> data) {
  return flash_program(address, data) == PortStatus::kOk ? FlashResult::kOk
                                                         : FlashResult::kProgramFailed;
}

std::span<const std::uint8_t> Stm32f4Flash::read(std::uint32_t address, std::size_t size) {
  constexpr std::uint32_t kFlashEnd = 0x08100000;
  if (address < kFlashBase || address > kFlashEnd || size > kFlashEnd - address) return {};
  return {reinterpret_cast<const std::uint8_t*>(static_cast<std::uintptr_t>(address)), size};
}

std::span<const std::uint8_t, 12> unique_id() {
  return std::span<const std::uint8_t, 12>(
      reinterpret_cast<const std::uint8_t*>(reg::kUniqueIdAddress), 12);
}

}  // namespace flutterscan::firmware::stm32f4
