// Clock setup, flash programming, the independent watchdog and the emergency
// LED shutdown of the stm32f4 images, written from RM0090 (6: RCC, 3: flash
// interface, 21: IWDG, 10: DMA).

#include "flutterscan/firmware/stm32f4/system.hpp"

#include <cstring>

#include "flutterscan/firmware/flash.hpp"
#include "flutterscan/firmware/stm32f4/hardware_math.hpp"
#include "flutterscan/firmware/stm32f4/registers.hpp"
#include "flutterscan/firmware/stm32f4/stm32f4_board.hpp"

namespace flutterscan::firmware::stm32f4 {

namespace {

/// Polls of a ready flag before giving up. A poll is a few cycles at 16..168
/// MHz, so this is tens of milliseconds: far beyond HSE start-up (~2 ms) and
/// PLL lock (~0.1 ms), far below the watchdog.
constexpr std::uint32_t kReadyPolls = 500'000;
/// Polls of FLASH_SR.BSY: a 16 KiB sector erase takes up to ~0.5 s (DS8626
/// table 42, x32); the CPU stalls on flash fetches meanwhile, so this bound
/// (several seconds at 168 MHz) only catches a controller that never finishes.
constexpr std::uint32_t kFlashPolls = 200'000'000;

/// \brief Waits until (register & mask) == value; false after `polls` reads.
bool wait_for(std::uintptr_t address, std::uint32_t mask, std::uint32_t value,
              std::uint32_t polls = kReadyPolls) {
  for (std::uint32_t i = 0; i < polls; ++i)
    if ((reg::at(address) & mask) == value) return true;
  return false;
}

ClockResult hsi_only() {
  // Back to HSI with every bus at /1 (the reset state), PLL off.
  reg::modify(reg::rcc::kCfgr, reg::rcc::kCfgrSwMask, reg::rcc::kCfgrSwHsi);
  wait_for(reg::rcc::kCfgr, reg::rcc::kCfgrSwsMask, 0);
  reg::modify(reg::rcc::kCfgr, reg::rcc::kCfgrPrescalerMask, 0);
  reg::clear_bits(reg::rcc::kCr, reg::rcc::kCrPllOn);
  return {ClockSource::kHsi, clock_tree(kHsiHz, 0, BusPrescalers{1, 1, 1})};
}

}  // namespace

ClockResult init_clocks() {
  static_assert(pll_valid(kPllFromHse) && pll_valid(kPllFromHsi));
  // HSI is on and SYSCLK after reset. Regulator scale 1 (RM0090 5.1.4) for 168 MHz.
  reg::set_bits(reg::rcc::kApb1Enr, reg::rcc::kApb1EnrPwr);
  (void)reg::read(reg::rcc::kApb1Enr);  // the clock enable takes effect after a bus cycle
  reg::set_bits(reg::pwr::kCr, reg::pwr::kCrVos);

  reg::set_bits(reg::rcc::kCr, reg::rcc::kCrHseOn);
  const bool hse = wait_for(reg::rcc::kCr, reg::rcc::kCrHseRdy, reg::rcc::kCrHseRdy);
  if (!hse) reg::clear_bits(reg::rcc::kCr, reg::rcc::kCrHseOn);
  const PllConfig& pll = hse ? kPllFromHse : kPllFromHsi;

  reg::clear_bits(reg::rcc::kCr, reg::rcc::kCrPllOn);
  if (!wait_for(reg::rcc::kCr, reg::rcc::kCrPllRdy, 0)) return hsi_only();
  reg::at(reg::rcc::kPllCfgr) = pllcfgr_value(pll, hse);
  reg::set_bits(reg::rcc::kCr, reg::rcc::kCrPllOn);
  if (!wait_for(reg::rcc::kCr, reg::rcc::kCrPllRdy, reg::rcc::kCrPllRdy)) return hsi_only();

  const BusPrescalers buses;
  const ClockTree tree = clock_tree(pll, buses);
  // Wait states before the clock goes up (RM0090 3.5.1), read back to be sure.
  const std::uint32_t latency = flash_wait_states(tree.hclk_hz);
  reg::at(reg::flash::kAcr) =
      latency | reg::flash::kAcrPrftEn | reg::flash::kAcrIcEn | reg::flash::kAcrDcEn;
  if (!wait_for(reg::flash::kAcr, reg::flash::kAcrLatencyMask, latency)) return hsi_only();

  reg::modify(reg::rcc::kCfgr, reg::rcc::kCfgrPrescalerMask, cfgr_prescaler_bits(buses));
  reg::modify(reg::rcc::kCfgr, reg::rcc::kCfgrSwMask, reg::rcc::kCfgrSwPll);
  if (!wait_for(reg::rcc::kCfgr, reg::rcc::kCfgrSwsMask, reg::rcc::kCfgrSwsPll)) return hsi_only();
  return {hse ? ClockSource::kHsePll : ClockSource::kHsiPll, tree};
}

// ---------------------------------------------------------------------------
// Flash (RM0090 3.6)

namespace {

bool flash_unlock() {
  if ((reg::at(reg::flash::kCr) & reg::flash::kCrLock) == 0) return true;
  reg::at(reg::flash::kKeyr) = reg::flash::kKey1;
  reg::at(reg::flash::kKeyr) = reg::flash::kKey2;
  return (reg::at(reg::flash::kCr) & reg::flash::kCrLock) == 0;
}

void flash_lock() {
  reg::set_bits(reg::flash::kCr, reg::flash::kCrLock);
}

bool flash_wait_idle() {
  return wait_for(reg::flash::kSr, reg::flash::kSrBsy, 0, kFlashPolls);
}

/// The data cache may hold lines of the erased or programmed area: flush it (RM0090 3.5.2).
void flash_reset_data_cache() {
  reg::clear_bits(reg::flash::kAcr, reg::flash::kAcrDcEn);
  reg::set_bits(reg::flash::kAcr, reg::flash::kAcrDcRst);
  reg::clear_bits(reg::flash::kAcr, reg::flash::kAcrDcRst);
  reg::set_bits(reg::flash::kAcr, reg::flash::kAcrDcEn);
}

}  // namespace

PortStatus flash_erase_sector(int sector) {
  // Never the bootloader's sector, never beyond the part.
  if (sector < 1 || sector > 11) return PortStatus::kError;
  if (!flash_wait_idle() || !flash_unlock()) return PortStatus::kError;
  reg::at(reg::flash::kSr) = reg::flash::kSrErrors | reg::flash::kSrEop;  // write 1 to clear
  reg::at(reg::flash::kCr) = reg::flash::kCrSer | reg::flash::kCrPsizeX32 |
                             (static_cast<std::uint32_t>(sector) << reg::flash::kCrSnbShift);
  reg::set_bits(reg::flash::kCr, reg::flash::kCrStrt);
  const bool done = flash_wait_idle();
  const bool errors = (reg::at(reg::flash::kSr) & reg::flash::kSrErrors) != 0;
  reg::clear_bits(reg::flash::kCr, reg::flash::kCrSer | reg::flash::kCrSnbMask);
  flash_lock();
  flash_reset_data_cache();
  return done && !errors ? PortStatus::kOk : PortStatus::kError;
}

PortStatus flash_program(std::uint32_t address, std::span<const std::uint8_t> data) {
  if (data.empty()) return PortStatus::kOk;
  if (address % kFlashProgramAlignment != 0 || flash_sector_of(address) < 1 ||
      flash_sector_of(address + static_cast<std::uint32_t>(data.size()) - 1) < 1)
    return PortStatus::kError;
  if (!flash_wait_idle() || !flash_unlock()) return PortStatus::kError;
  reg::at(reg::flash::kSr) = reg::flash::kSrErrors | reg::flash::kSrEop;
  reg::at(reg::flash::kCr) = reg::flash::kCrPg | reg::flash::kCrPsizeX32;
  bool ok = true;
  for (std::size_t offset = 0; ok && offset < data.size(); offset += 4) {
    std::uint32_t word = 0xFFFFFFFF;
    std::memcpy(&word, data.data() + offset, data.size() - offset < 4 ? data.size() - offset : 4);
    volatile std::uint32_t& cell = reg::at(address + offset);
    cell = word;
    ok = flash_wait_idle() && (reg::at(reg::flash::kSr) & reg::flash::kSrErrors) == 0;
  }
  reg::clear_bits(reg::flash::kCr, reg::flash::kCrPg);
  flash_lock();
  flash_reset_data_cache();
  for (std::size_t offset = 0; ok && offset + 4 <= data.size(); offset += 4) {
    std::uint32_t word;
    std::memcpy(&word, data.data() + offset, 4);
    ok = reg::at(address + offset) == word;
  }
  return ok ? PortStatus::kOk : PortStatus::kError;
}

PortStatus otp_program(std::uint32_t address, std::span<const std::uint32_t> words) {
  constexpr std::uint32_t kOtpBase = 0x1FFF7800;
  constexpr std::uint32_t kOtpDataBytes = 512;
  if (address % 4 != 0 || address < kOtpBase ||
      address + 4 * words.size() > kOtpBase + kOtpDataBytes)
    return PortStatus::kError;
  if (!flash_wait_idle() || !flash_unlock()) return PortStatus::kError;
  reg::at(reg::flash::kSr) = reg::flash::kSrErrors | reg::flash::kSrEop;
  reg::at(reg::flash::kCr) = reg::flash::kCrPg | reg::flash::kCrPsizeX32;
  bool ok = true;
  for (std::size_t i = 0; ok && i < words.size(); ++i) {
    reg::at(address + 4 * static_cast<std::uint32_t>(i)) = words[i];
    ok = flash_wait_idle() && (reg::at(reg::flash::kSr) & reg::flash::kSrErrors) == 0;
  }
  reg::clear_bits(reg::flash::kCr, reg::flash::kCrPg);
  flash_lock();
  for (std::size_t i = 0; ok && i < words.size(); ++i)
    ok = reg::at(address + 4 * static_cast<std::uint32_t>(i)) == words[i];
  return ok ? PortStatus::kOk : PortStatus::kError;
}

// ---------------------------------------------------------------------------

bool start_independent_watchdog(std::uint32_t timeout_ms) {
  const WatchdogSetting setting = watchdog_setting(timeout_ms);
  if (!setting.ok) return false;
  reg::set_bits(reg::dbgmcu::kApb1Fz, reg::dbgmcu::kApb1FzIwdgStop);
  reg::at(reg::iwdg::kKr) = reg::iwdg::kKeyStart;  // also starts the LSI
  reg::at(reg::iwdg::kKr) = reg::iwdg::kKeyUnlock;
  const auto updating = [] {
    return (reg::read(reg::iwdg::kSr) & (reg::iwdg::kSrPvu | reg::iwdg::kSrRvu)) != 0;
  };
  for (int i = 0; i < 1'000'000 && updating(); ++i) {
  }
  reg::at(reg::iwdg::kPr) = setting.pr;
  reg::at(reg::iwdg::kRlr) = setting.rlr;
  // The new values reach the LSI domain within a few LSI cycles (RM0090 21.4.4).
  for (int i = 0; i < 1'000'000 && updating(); ++i) {
  }
  reg::at(reg::iwdg::kKr) = reg::iwdg::kKeyReload;
  return true;
}

void emergency_leds_off() {
  constexpr std::uintptr_t slot_stream = reg::dma::stream(reg::dma::kDma2, kTim1UpRoute.stream);
  reg::clear_bits(reg::tim::kTim1 + reg::tim::kCr1, reg::tim::kCr1Cen);
  reg::clear_bits(slot_stream + reg::dma::kSxCr, reg::dma::kCrEn);
  // Reset every pin an LED may be on (PC0..PC3), whatever the board map says.
  reg::at(reg::gpio::port(kLedPort) + reg::gpio::kBsrr) = 0xFu << 16;
}

}  // namespace flutterscan::firmware::stm32f4
