#pragma once
// What the fw-qemu image is: QEMU 7.2's netduinoplus2 (an STM32F405RG) with the
// LED enable pins on GPIOA. Shared by the image and the host-side QEMU test,
// so both agree on pins and versions. Host-compilable (no registers here).
//
// The firmware version comes from the top-level project(VERSION ...) through
// the FLUTTERSCAN_VERSION_* definitions of the flutterscan_firmware_qemu_board
// CMake target.

#include <cstdint>

#include "flutterscan/common/image_header.hpp"
#include "flutterscan/firmware/settings.hpp"

#ifndef FLUTTERSCAN_VERSION_MAJOR
#error "link flutterscan_firmware_qemu_board: it defines FLUTTERSCAN_VERSION_*"
#endif

namespace flutterscan::firmware::qemu {

/// SYSCLK of QEMU's netduinoplus2 (fixed by the machine model, whatever RCC says);
/// SysTick runs on it with CLKSOURCE = 1.
inline constexpr std::uint32_t kSysClockHz = 168'000'000;
/// SysTick interrupt period while no slot table plays (the clock's tick).
inline constexpr std::uint32_t kIdleTickUs = 1'000;
/// Board id reported by GetInfo for the QEMU image.
inline constexpr std::uint16_t kQemuBoardId = kBoardIdQemuNetduinoplus2;
/// Bytes of the RAM array standing in for the config flash page (QEMU does not
/// model the flash interface, so SaveConfig lasts until reset).
inline constexpr std::size_t kConfigPageSize = 4096;

/// \brief The board configuration of the fw-qemu image: three LEDs on PA0, PA1, PA2.
constexpr BoardConfig qemu_board_config() {
  BoardConfig board;
  board.pins = LedPinMap{3, {0, 1, 2, 3}};
  board.board_id = kQemuBoardId;
  board.firmware_major = FLUTTERSCAN_VERSION_MAJOR;
  board.firmware_minor = FLUTTERSCAN_VERSION_MINOR;
  board.firmware_patch = FLUTTERSCAN_VERSION_PATCH;
  return board;
}

}  // namespace flutterscan::firmware::qemu
