#pragma once
// The configuration in flash: a fixed little-endian image of ControllerSettings
// ending in a CRC-32 over every byte before it. Loading refuses an image whose
// magic, version, size, CRC or contents are wrong; the caller then uses defaults.
// Two copies, one per config page (Port::config_page_size, kConfigCopies): each
// page holds an image at offset 0 and, right after it, a ConfigCommit with a
// sequence number, written only once the image reads back right. SaveConfig
// erases and rewrites the page that does not hold the newest valid copy, so a
// power loss at any point loses at most the save in progress; loading takes
// the valid copy with the highest sequence. A page with a valid image and an
// erased commit (written by firmware before the two copies, or cut off just
// before its commit) counts as sequence 0.
// Freestanding C++20: no heap, no exceptions, no RTTI.

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "flutterscan/common/result.hpp"
#include "flutterscan/firmware/port.hpp"
#include "flutterscan/firmware/settings.hpp"

namespace flutterscan::firmware {

/// \brief Why a stored configuration was not used.
enum class ConfigError : std::uint8_t {
  kNone,
  kEmpty,        ///< the page is erased: nothing was ever saved
  kReadFailed,   ///< the flash could not be read
  kBadMagic,     ///< not a configuration image
  kBadVersion,   ///< an image format this firmware does not know
  kBadSize,      ///< the image's size field is wrong
  kCrcMismatch,  ///< the CRC does not match: the image is corrupt
  kBadContent,   ///< CRC fine, but a value is out of range for this board
};

/// \brief One code table entry in the image.
struct StoredCodeImage {
  std::uint8_t present;
  std::uint8_t leds;
  std::uint16_t length;
  std::array<std::uint8_t, kMaxSlots> masks;
};

/// \brief The configuration image, byte for byte as in flash.
struct ConfigImage {
  std::uint32_t magic;           ///< kConfigMagic
  std::uint16_t format_version;  ///< kConfigFormatVersion
  std::uint16_t image_size;      ///< sizeof(ConfigImage)
  std::uint8_t selected_code;
  std::uint8_t sync_mode;
  std::uint8_t strobe_active_low;
  std::uint8_t slot_time_source;
  std::uint32_t slot_time_us;
  std::uint32_t frame_period_us;
  std::array<std::uint16_t, kMaxLeds> brightness_permille;
  std::array<std::uint32_t, kMaxLeds> max_on_time_us;
  std::array<std::uint16_t, kMaxLeds> max_duty_permille;
  std::array<StoredCodeImage, protocol::kMaxCodes> codes;
  std::uint32_t crc32;  ///< CRC-32 of every byte before this field
};

inline constexpr std::uint32_t kConfigMagic = 0x46435346;  // "FSCF" little-endian

/// \brief The commit record after a copy's image: the copy is complete.
struct ConfigCommit {
  std::uint32_t magic;      ///< kConfigCommitMagic
  std::uint32_t sequence;   ///< one more than the copy it replaces (serial arithmetic)
  std::uint32_t image_crc;  ///< the image's crc32 field
  std::uint32_t crc32;      ///< CRC-32 of the three fields before
};
inline constexpr std::uint32_t kConfigCommitMagic = 0x43435346;  // "FSCC" little-endian
inline constexpr std::uint16_t kConfigFormatVersion = 1;

static_assert(protocol::WireStruct<StoredCodeImage> && sizeof(StoredCodeImage) == 260);
static_assert(protocol::WireStruct<ConfigImage> && sizeof(ConfigImage) == 2136);
static_assert(protocol::WireStruct<ConfigCommit> && sizeof(ConfigCommit) == 16);
static_assert(offsetof(ConfigImage, slot_time_us) == 12 && offsetof(ConfigImage, codes) == 52 &&
              offsetof(ConfigImage, crc32) == sizeof(ConfigImage) - 4);

/// \brief The image of `settings`, CRC filled in.
ConfigImage encode_config(const ControllerSettings& settings);

/// \brief The settings in `bytes` (at least sizeof(ConfigImage) of them), or why not.
Result<ControllerSettings, ConfigError> decode_config(std::span<const std::uint8_t> bytes,
                                                      const BoardConfig& board);

/// \brief Writes `settings` as the newest copy into the config page not holding
/// the newest copy load_config would use on `board` (erase, image, read back,
/// commit, read back). Returns the image's CRC, or kFlashError.
Result<std::uint32_t, protocol::Status> save_config(Port& port, const ControllerSettings& settings,
                                                    const BoardConfig& board);

/// \brief The newest valid copy of the config pages (see decode_config); kEmpty
/// if both are erased, otherwise the first copy's error if neither is valid.
Result<ControllerSettings, ConfigError> load_config(Port& port, const BoardConfig& board);

}  // namespace flutterscan::firmware
