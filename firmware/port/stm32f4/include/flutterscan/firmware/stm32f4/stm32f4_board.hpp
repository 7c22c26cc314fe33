#pragma once
// The product board: an STM32F405RG (LQFP64) with an 8 MHz crystal. Pins and
// alternate functions from the F405 datasheet (DS8626, table 9); the flash
// map from RM0090 (table 5: sectors 0..3 are 16 KiB, 4 is 64 KiB, 5..11 are
// 128 KiB). Host-compilable: the image and the host tests share it.
//
//   PC0..PC3  LED enable lines 0..3 (push-pull outputs, one GPIO port so one
//             BSRR word sets one slot; the board needs pull-downs so the LEDs
//             stay dark while the pins float during reset)
//   PC6..PC9  TIM3_CH1..CH4 (AF2): brightness PWM to each LED driver's
//             dimming input (RC-filtered on the board)
//   PA5       TIM2_CH1 (AF1): camera strobe / exposure-active input
//   PB10      TIM2_CH3 (AF1): camera trigger output (master mode)
//   PA0, PA1  TIM5_CH1, CH2 (AF2): quadrature encoder A, B
//   PA11/PA12 USB OTG FS DM/DP, PA9 VBUS sense (for the USB driver to come)
//   PA13/PA14 SWD

#include <array>
#include <cstddef>
#include <cstdint>

#include "flutterscan/common/image_header.hpp"
#include "flutterscan/firmware/settings.hpp"

#ifndef FLUTTERSCAN_VERSION_MAJOR
#error "link flutterscan_firmware_stm32f4_board: it defines FLUTTERSCAN_VERSION_*"
#endif

namespace flutterscan::firmware::stm32f4 {

/// Board id of the STM32F405 product board (GetInfo; the image header).
inline constexpr std::uint16_t kBoardId = kBoardIdStm32f405;

// GPIO port indices (0 = A).
inline constexpr int kPortA = 0;
inline constexpr int kPortB = 1;
inline constexpr int kPortC = 2;

/// The LEDs' GPIO port (every slot is one write to its BSRR).
inline constexpr int kLedPort = kPortC;
/// Brightness PWM: TIM3 channel k + 1 on PC6 + k (AF2).
inline constexpr int kPwmPort = kPortC;
inline constexpr int kPwmFirstPin = 6;
inline constexpr std::uint32_t kPwmAf = 2;
/// Strobe input PA5 = TIM2_CH1 (AF1).
inline constexpr int kStrobePort = kPortA;
inline constexpr int kStrobePin = 5;
inline constexpr std::uint32_t kStrobeAf = 1;
/// Camera trigger output PB10 = TIM2_CH3 (AF1).
inline constexpr int kTriggerPort = kPortB;
inline constexpr int kTriggerPin = 10;
inline constexpr std::uint32_t kTriggerAf = 1;
/// Encoder PA0 = TIM5_CH1, PA1 = TIM5_CH2 (AF2).
inline constexpr int kEncoderPort = kPortA;
inline constexpr int kEncoderPinA = 0;
inline constexpr int kEncoderPinB = 1;
inline constexpr std::uint32_t kEncoderAf = 2;

/// Crystal on OSC_IN/OSC_OUT.
inline constexpr std::uint32_t kHseHz = 8'000'000;

// ---------------------------------------------------------------------------
// Flash map (RM0090 table 5, 1 MiB part)

inline constexpr std::uint32_t kFlashBase = 0x08000000;
/// Bootloader: sector 0 (16 KiB).
inline constexpr std::uint32_t kBootloaderBase = kFlashBase;
inline constexpr std::uint32_t kBootloaderSize = 16 * 1024;
/// Config page: sector 1 (16 KiB, so SaveConfig erases 16 KiB, not 64 or 128);
/// the second copy is in sector 11 (kConfigSectors), no other 16 KiB sector
/// being free: SaveConfig erases one of them, the one without the newest copy.
inline constexpr int kConfigSector = 1;
inline constexpr std::uint32_t kConfigBase = 0x08004000;
inline constexpr std::uint32_t kConfigSize = 16 * 1024;
/// Application: from sector 2 on, at most 64 KiB (sectors 2, 3 and half of 4).
inline constexpr std::uint32_t kAppBase = kStm32f405AppRegion.load_address;
inline constexpr std::uint32_t kAppMaxSize = kStm32f405AppRegion.max_size;
/// The app's vector table follows its image header (VTOR needs 512-byte
/// alignment for the F405's 98 vectors: PM0214 4.4.4).
inline constexpr std::uint32_t kAppVectorOffset = 0x200;
/// First sector of the application (what a firmware update erases from).
inline constexpr int kAppFirstSector = 2;

/// \brief Start address of flash sector `sector` (0..11) of the 1 MiB STM32F405.
constexpr std::uint32_t flash_sector_base(int sector) {
  if (sector < 4) return kFlashBase + static_cast<std::uint32_t>(sector) * 16 * 1024;
  if (sector == 4) return kFlashBase + 64 * 1024;
  return kFlashBase + static_cast<std::uint32_t>(sector - 4) * 128 * 1024;
}

/// \brief Bytes in flash sector `sector` (0..11).
constexpr std::uint32_t flash_sector_size(int sector) {
  return sector < 4 ? 16 * 1024 : sector == 4 ? 64 * 1024 : 128 * 1024;
}

/// \brief The sector holding `address`, or -1 outside the 1 MiB of flash.
constexpr int flash_sector_of(std::uint32_t address) {
  for (int s = 0; s < 12; ++s)
    if (address >= flash_sector_base(s) && address - flash_sector_base(s) < flash_sector_size(s))
      return s;
  return -1;
}

/// The config pages, one copy each (Port::read_config_page's `copy`): sector 1,
/// and the last sector, which no application image can reach.
inline constexpr std::array<int, 2> kConfigSectors{kConfigSector, 11};

// ---------------------------------------------------------------------------
// Bootloader hand-off: a word at the bottom of SRAM that neither image's
// .data/.bss covers (both linker scripts start SRAM above it). The app writes
// kBootRequestMagic there and resets; the bootloader stays in DFU if it finds it.
inline constexpr std::uint32_t kBootRequestAddress = 0x20000000;
inline constexpr std::uint32_t kBootRequestReserved = 32;  ///< bytes kept free there
inline constexpr std::uint32_t kBootRequestMagic = 0xB007DF11;

/// \brief The security floor's cells (security_floor.hpp): OTP block 0 (RM0090
/// 3.8: 16 blocks of 32 one-time-programmable bytes from 0x1FFF7800; its lock
/// byte at 0x1FFF7A00 is left unprogrammed, so the floor can still rise).
inline constexpr std::uint32_t kSecurityFloorAddress = 0x1FFF7800;
/// \brief The product image's security_version (image header). Raise it in a
/// release that must never be rolled back from (a safety fix): once such an
/// image confirms itself on a board, no older one runs there again.
inline constexpr std::uint8_t kImageSecurityVersion = 1;

/// \brief The watchdog timeout the bootloader starts the IWDG with just before
/// it jumps to the application (at the nominal 32 kHz LSI), so that an image
/// that hangs or faults before it feeds the watchdog is reset, and the third
/// such reset in a row keeps DFU mode: back in DFU mode about 3 x 2 s after the
/// first start (LSI 17-47 kHz: 1.4-3.8 s each). Longer than the application's
/// start-up before its own start_watchdog (4 s), shorter than 10 s / 3.
inline constexpr std::uint32_t kBootWatchdogTimeoutMs = 2'000;
/// The BootRecord (boot_decision.hpp: unconfirmed application starts, watchdog
/// resets in a row, the reset flags) right after the hand-off word, inside the
/// same reserved 32 bytes (both linker scripts start SRAM at 0x20000020).
inline constexpr std::uint32_t kBootRecordAddress = kBootRequestAddress + 4;
/// Recovery pin: PB2 (BOOT1, unused by the ROM while BOOT0 is low), 10 kOhm to
/// ground on the board; a jumper to 3.3 V at reset keeps the bootloader in DFU mode.
inline constexpr int kRecoveryPort = 1;  // GPIOB
inline constexpr int kRecoveryPin = 2;

/// \brief The board configuration of the product image: four LEDs on PC0..PC3
/// (boards with three LEDs leave PC3 unconnected; the code sets led_count 3).
constexpr BoardConfig stm32f4_board_config() {
  BoardConfig board;
  board.pins = LedPinMap{3, {0, 1, 2, 3}};
  board.board_id = kBoardId;
  board.firmware_major = FLUTTERSCAN_VERSION_MAJOR;
  board.firmware_minor = FLUTTERSCAN_VERSION_MINOR;
  board.firmware_patch = FLUTTERSCAN_VERSION_PATCH;
  return board;
}

}  // namespace flutterscan::firmware::stm32f4
