// Write protection of flash sector 0, set by the bootloader itself on the
// first boot (docs/hardware.md, "Write protection of sector 0"). From RM0090
// 3.6.2 (programming user option bytes) and 3.9.6-3.9.7 (OPTKEYR, OPTCR).

#include "sector0_protection.hpp"

#include <cstdint>

#include "flutterscan/firmware/stm32f4/registers.hpp"

namespace {

namespace reg = flutterscan::firmware::stm32f4::reg;

/// Polls of FLASH_SR.BSY. An option-byte write takes some 16 ms at most
/// (DS8626: t_prog of the option bytes); this bound is far above that at 16 MHz.
constexpr int kBusyPolls = 10'000'000;

bool wait_not_busy() {
  for (int i = 0; i < kBusyPolls; ++i)
    if ((reg::read(reg::flash::kSr) & reg::flash::kSrBsy) == 0) return true;
  return false;
}

}  // namespace

bool protect_bootloader_sector() {
  const std::uint32_t nwrp0 = reg::flash::optcr_nwrp(0);
  if ((reg::read(reg::flash::kOptcr) & nwrp0) == 0) return true;  // already protected
  if (!wait_not_busy()) return false;
  if ((reg::read(reg::flash::kOptcr) & reg::flash::kOptcrOptLock) != 0) {
    reg::at(reg::flash::kOptKeyr) = reg::flash::kOptKey1;
    reg::at(reg::flash::kOptKeyr) = reg::flash::kOptKey2;
    if ((reg::read(reg::flash::kOptcr) & reg::flash::kOptcrOptLock) != 0) return false;
  }
  // Only nWRP0 changes: RDP, BOR level, user bits and the other sectors' nWRP as they are.
  reg::clear_bits(reg::flash::kOptcr, nwrp0);
  reg::set_bits(reg::flash::kOptcr, reg::flash::kOptcrOptStrt);
  const bool done = wait_not_busy();
  reg::set_bits(reg::flash::kOptcr, reg::flash::kOptcrOptLock);
  return done && (reg::read(reg::flash::kOptcr) & nwrp0) == 0;
}
