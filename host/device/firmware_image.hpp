#pragma once
// Application images for the DFU flasher: loaded from .bin (the bytes from the
// load address on), Intel .hex or .elf (ELF32 ARM, PT_LOAD segments at their
// physical addresses), gaps filled with 0 as objcopy -O binary does, then
// checked with the bootloader's own checker (common image_header.hpp) before
// any device is touched.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "device/device_error.hpp"
#include "flutterscan/common/image_header.hpp"

namespace flutterscan::device {

/// \brief A checked application image, as it will be written from the region's start.
struct FirmwareImage {
  std::vector<std::uint8_t> bytes;  ///< from region.load_address, image_size bytes
  ImageHeader header{};
  std::string source;  ///< where it came from (file name), for messages
};

/// \brief How a file is read.
enum class ImageFormat { kBinary, kIntelHex, kElf };

/// \brief The format from the file's content (ELF magic, ':' records) or, failing
/// that, its extension (.bin, .hex/.ihex, .elf).
ImageFormat guess_image_format(const std::filesystem::path& path,
                               std::span<const std::uint8_t> content);

/// \brief The flat image from `content` in `format` for `region` (bytes from
/// region.load_address on). kBadInput naming the record, segment or offset at fault.
Expected<std::vector<std::uint8_t>> flatten_image(std::span<const std::uint8_t> content,
                                                  ImageFormat format, const AppRegion& region,
                                                  const std::string& source);

/// \brief Reads `path`, flattens it and checks its header for `region`'s board
/// (magic, header CRC, board id, layout, image CRC). kBadInput with the reason.
Expected<FirmwareImage> load_firmware_image(const std::filesystem::path& path,
                                            const AppRegion& region);

/// \brief The same from bytes already in memory (`source` names them in messages).
Expected<FirmwareImage> check_firmware_image(std::vector<std::uint8_t> flat,
                                             const AppRegion& region, const std::string& source);

/// \brief Why check_image refused, in words.
std::string image_check_text(ImageCheck check);

/// \brief The application region of board `board_id`, if it has one that takes DFU updates.
std::optional<AppRegion> app_region_for_board(std::uint16_t board_id);

}  // namespace flutterscan::device
