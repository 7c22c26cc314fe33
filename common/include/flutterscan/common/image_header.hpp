#pragma once
// The header at the start of the application region: what the bootloader
// checks before it jumps to an application (and at DFU manifest), and what the
// host flasher checks before it flashes one: the same checker on both sides. The linker places it
// first in the app image with the CRC fields zero; the post-build step (stamp_image.cmake) fills
// image_size and both CRCs (firmware/port/stm32f4). Freestanding.
//
// Layout of an application image (the .bin as flashed at kAppBase):
//   [0, sizeof(ImageHeader))          this header
//   [.., vector_table_offset)          zero padding
//   [vector_table_offset, image_size)  vector table, code, data load image
// image_crc32 covers [vector_table_offset, image_size); header_crc32 covers
// the header bytes before it. CRC-32 is the zlib one (common/crc32.hpp).

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>

#include "flutterscan/common/crc32.hpp"

namespace flutterscan {

/// Board ids (image header, GetInfo's board_id): never reused or renumbered.
inline constexpr std::uint16_t kBoardIdStm32f405 = 1;          ///< the product board (fw-stm32f405)
inline constexpr std::uint16_t kBoardIdQemuNetduinoplus2 = 2;  ///< QEMU's netduinoplus2 (fw-qemu)

/// \brief Where a board's application image lives: what check_image() needs.
struct AppRegion {
  std::uint16_t board_id;
  std::uint32_t load_address;  ///< the header's load_address (the DFU download's block 0)
  std::uint32_t max_size;      ///< bytes the region holds (check_image's max_size)
};

/// The STM32F405 product board: application from flash sector 2, at most 64 KiB.
inline constexpr AppRegion kStm32f405AppRegion{kBoardIdStm32f405, 0x08008000, 64 * 1024};

/// "FSAP" little-endian: a flutterscan application image.
inline constexpr std::uint32_t kImageMagic = 0x50415346;
inline constexpr std::uint16_t kImageHeaderVersion = 1;

/// \brief The application image header, byte for byte as in flash (little-endian).
struct ImageHeader {
  std::uint32_t magic;           ///< kImageMagic
  std::uint16_t header_version;  ///< kImageHeaderVersion
  std::uint16_t header_size;     ///< sizeof(ImageHeader)
  std::uint16_t board_id;        ///< the board the image is built for
  std::uint8_t version_major;
  std::uint8_t version_minor;
  std::uint8_t version_patch;
  /// Anti-rollback: the bootloader starts, and DFU manifests, no image whose
  /// security_version is below the newest confirmed image's (the board's
  /// security floor). Images from before this field carry 0.
  std::uint8_t security_version;
  std::uint8_t reserved[2];
  std::uint32_t load_address;         ///< where the image runs (kAppBase)
  std::uint32_t vector_table_offset;  ///< from load_address; 512-byte aligned
  std::uint32_t image_size;           ///< bytes from load_address to the image's end
  std::uint32_t image_crc32;          ///< CRC-32 of [vector_table_offset, image_size)
  std::uint32_t header_crc32;         ///< CRC-32 of every header byte before this field
};

static_assert(sizeof(ImageHeader) == 36);
static_assert(offsetof(ImageHeader, board_id) == 8 && offsetof(ImageHeader, load_address) == 16 &&
              offsetof(ImageHeader, vector_table_offset) == 20 &&
              offsetof(ImageHeader, image_size) == 24 && offsetof(ImageHeader, image_crc32) == 28 &&
              offsetof(ImageHeader, header_crc32) == 32);

/// \brief Why an image is refused.
enum class ImageCheck : std::uint8_t {
  kOk,
  kTooShort,    ///< fewer bytes than a header, or than image_size says
  kBadMagic,    ///< not an application image
  kBadHeader,   ///< unknown header version or size, or header CRC mismatch
  kWrongBoard,  ///< built for another board
  kBadLayout,   ///< vector table offset or size impossible for the region
  kImageCrcMismatch,
};

/// \brief The header at the start of `image` (which must hold sizeof(ImageHeader) bytes).
inline ImageHeader read_image_header(std::span<const std::uint8_t> image) {
  ImageHeader header{};
  std::memcpy(&header, image.data(), sizeof header);
  return header;
}

/// \brief CRC-32 of the header bytes before header_crc32.
inline std::uint32_t image_header_crc(const ImageHeader& header) {
  return crc32(std::span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>(&header),
                                             offsetof(ImageHeader, header_crc32)));
}

/// \brief Checks `image` (the bytes from the load address on, at least
/// image_size of them) for board `board_id` in a region of `max_size` bytes.
inline ImageCheck check_image(std::span<const std::uint8_t> image, std::uint16_t board_id,
                              std::uint32_t max_size) {
  if (image.size() < sizeof(ImageHeader)) return ImageCheck::kTooShort;
  const ImageHeader h = read_image_header(image);
  if (h.magic != kImageMagic) return ImageCheck::kBadMagic;
  if (h.header_version != kImageHeaderVersion || h.header_size != sizeof(ImageHeader) ||
      h.header_crc32 != image_header_crc(h))
    return ImageCheck::kBadHeader;
  if (h.board_id != board_id) return ImageCheck::kWrongBoard;
  if (h.vector_table_offset < sizeof(ImageHeader) || h.vector_table_offset % 512 != 0 ||
      h.image_size > max_size || h.image_size <= h.vector_table_offset + 8)
    return ImageCheck::kBadLayout;
  if (image.size() < h.image_size) return ImageCheck::kTooShort;
  const auto payload = image.subspan(h.vector_table_offset, h.image_size - h.vector_table_offset);
  return crc32(payload) == h.image_crc32 ? ImageCheck::kOk : ImageCheck::kImageCrcMismatch;
}

/// \brief Fills image_size (= image.size()), image_crc32 and header_crc32 of the
/// header at the start of `image`; false if the image is too short for its layout.
inline bool stamp_image(std::span<std::uint8_t> image) {
  if (image.size() < sizeof(ImageHeader)) return false;
  ImageHeader h = read_image_header(image);
  if (h.vector_table_offset >= image.size()) return false;
  h.image_size = static_cast<std::uint32_t>(image.size());
  h.image_crc32 = crc32(std::span<const std::uint8_t>(image).subspan(h.vector_table_offset));
  h.header_crc32 = image_header_crc(h);
  std::memcpy(image.data(), &h, sizeof h);
  return true;
}

}  // namespace flutterscan
