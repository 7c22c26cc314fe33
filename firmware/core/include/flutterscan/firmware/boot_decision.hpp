#pragma once
// What the bootloader does at reset: start the application only if it was not
// asked to stay (the application's hand-off word: EnterBootloader, DFU_DETACH)
// and the application region holds an image the common checker accepts for
// this board; otherwise stay in DFU mode, so an interrupted flash can always
// be repeated. Freestanding C++20: no heap, no exceptions, no RTTI.

#include <cstdint>
#include <span>

#include "flutterscan/common/image_header.hpp"

namespace flutterscan::firmware {

/// \brief Where the bootloader goes.
enum class BootTarget : std::uint8_t { kApplication, kDfuMode };

/// \brief The decision for the bytes of `region` (`region_bytes`, max_size of
/// them) when the application asked for DFU mode (`dfu_requested`) or not.
inline BootTarget choose_boot_target(bool dfu_requested, std::span<const std::uint8_t> region_bytes,
                                     const AppRegion& region) {
  if (dfu_requested) return BootTarget::kDfuMode;
  return check_image(region_bytes, region.board_id, region.max_size) == ImageCheck::kOk
             ? BootTarget::kApplication
             : BootTarget::kDfuMode;
}

}  // namespace flutterscan::firmware
