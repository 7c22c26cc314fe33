#pragma once
// What the bootloader does at reset (docs/hardware.md, "Boot and recovery").
//
// It starts the application only if
// - the application did not ask for DFU mode (the hand-off word:
//   EnterBootloader, DFU_DETACH), and the boot pin is not held;
// - fewer than kMaxUnconfirmedStarts starts in a row went unconfirmed: the
//   application confirms itself (BootConfirmation) only once USB is configured
//   and has stayed so for kConfirmAfterConfiguredMs, so an image that hangs
//   (watchdog resets) or never brings USB up falls back to DFU mode by itself;
// - the region holds an image the common checker accepts for this board AND
//   that the jump can use: load address = the region's, vector table exactly
//   at kAppVectorTableOffset (the address the bootloader jumps through, so the
//   image CRC covers it), initial SP inside SRAM, reset vector a Thumb address
//   inside the image (check_boot_image).
// Otherwise it stays in DFU mode, so an interrupted or bad flash can always be
// repeated. Freestanding C++20: no heap, no exceptions, no RTTI.

#include <cstdint>
#include <cstring>
#include <span>

#include "flutterscan/common/image_header.hpp"

namespace flutterscan::firmware {

/// \brief Where the bootloader goes.
enum class BootTarget : std::uint8_t { kApplication, kDfuMode };

/// Where every application's vector table sits (after the header; VTOR needs
/// 512-byte alignment for the F405's 98 vectors, PM0214 4.4.4).
inline constexpr std::uint32_t kAppVectorTableOffset = 0x200;
/// SRAM1 + SRAM2 of the STM32F405 (RM0090 2.3.1): where the initial SP may point.
inline constexpr std::uint32_t kSramBase = 0x20000000;
inline constexpr std::uint32_t kSramEnd = 0x20020000;
/// Starts without a confirmation after which the bootloader stays in DFU mode.
inline constexpr std::uint32_t kMaxUnconfirmedStarts = 3;
/// USB configured this long (a host enumerated the device and kept it): confirmed.
inline constexpr std::uint32_t kConfirmAfterConfiguredMs = 3'000;

/// \brief What check_boot_image found.
enum class BootImageCheck : std::uint8_t {
  kOk,
  kImageRefused,       ///< check_image refused it (header, board, size, CRC)
  kWrongLoadAddress,   ///< linked for another address than the region's
  kWrongVectorOffset,  ///< vector table not where the bootloader jumps through
  kBadStackPointer,    ///< initial SP outside SRAM or misaligned
  kBadResetVector,     ///< reset vector not a Thumb address inside the image
};

/// \brief Whether the bootloader can start the image in `region_bytes`: the
/// common checker, then what the jump itself reads (see the file comment).
inline BootImageCheck check_boot_image(std::span<const std::uint8_t> region_bytes,
                                       const AppRegion& region) {
  if (check_image(region_bytes, region.board_id, region.max_size) != ImageCheck::kOk)
    return BootImageCheck::kImageRefused;
  const ImageHeader h = read_image_header(region_bytes);
  if (h.load_address != region.load_address) return BootImageCheck::kWrongLoadAddress;
  if (h.vector_table_offset != kAppVectorTableOffset) return BootImageCheck::kWrongVectorOffset;
  // check_image: image_size > offset + 8 and the CRC covers [offset, size).
  std::uint32_t sp = 0;
  std::uint32_t pc = 0;
  std::memcpy(&sp, region_bytes.data() + kAppVectorTableOffset, sizeof sp);
  std::memcpy(&pc, region_bytes.data() + kAppVectorTableOffset + 4, sizeof pc);
  if (sp <= kSramBase || sp > kSramEnd || sp % 8 != 0) return BootImageCheck::kBadStackPointer;
  const std::uint32_t code_begin = region.load_address + kAppVectorTableOffset + 8;
  const std::uint32_t code_end = region.load_address + h.image_size;
  const std::uint32_t target = pc & ~1u;
  if ((pc & 1u) == 0 || target < code_begin || target >= code_end)
    return BootImageCheck::kBadResetVector;
  return BootImageCheck::kOk;
}

/// \brief The record the bootloader and the application share across warm
/// resets (no-init SRAM after the hand-off word; random after power-on, which
/// the check word detects).
struct BootRecord {
  std::uint32_t magic;               ///< kBootRecordMagic
  std::uint32_t unconfirmed_starts;  ///< application starts since the last confirmation
  std::uint32_t check;               ///< ~(magic ^ unconfirmed_starts)
};
inline constexpr std::uint32_t kBootRecordMagic = 0xB0075EC0;

/// \brief Unconfirmed starts in `record`; 0 if it is not valid (power-on).
inline std::uint32_t unconfirmed_starts(const BootRecord& record) {
  if (record.magic != kBootRecordMagic ||
      record.check != ~(record.magic ^ record.unconfirmed_starts))
    return 0;
  return record.unconfirmed_starts;
}

/// \brief A valid record of `starts` unconfirmed starts.
inline BootRecord make_boot_record(std::uint32_t starts) {
  return {kBootRecordMagic, starts, ~(kBootRecordMagic ^ starts)};
}

/// \brief What the bootloader knows at reset.
struct BootInputs {
  bool dfu_requested = false;  ///< the application's hand-off word
  bool boot_pin_held = false;  ///< the recovery pin (docs/hardware.md)
  std::uint32_t unconfirmed_starts = 0;
  BootImageCheck image = BootImageCheck::kImageRefused;
};

/// \brief The decision, and the unconfirmed-start count to store before acting on it.
struct BootDecision {
  BootTarget target = BootTarget::kDfuMode;
  std::uint32_t unconfirmed_starts = 0;
};

/// \brief The bootloader's decision at reset.
inline BootDecision decide_boot(const BootInputs& in) {
  if (in.dfu_requested || in.boot_pin_held || in.image != BootImageCheck::kOk ||
      in.unconfirmed_starts >= kMaxUnconfirmedStarts)
    return {BootTarget::kDfuMode, in.unconfirmed_starts};
  return {BootTarget::kApplication, in.unconfirmed_starts + 1};  // this start is on trial
}

/// \brief The decision for the bytes of `region` (`region_bytes`, max_size of
/// them) when the application asked for DFU mode (`dfu_requested`) or not, no
/// pin held and no unconfirmed start.
inline BootTarget choose_boot_target(bool dfu_requested, std::span<const std::uint8_t> region_bytes,
                                     const AppRegion& region) {
  BootInputs in;
  in.dfu_requested = dfu_requested;
  in.image = check_boot_image(region_bytes, region);
  return decide_boot(in).target;
}

/// \brief The application's side: confirms itself once USB has been configured
/// (a host enumerated it and kept it) for kConfirmAfterConfiguredMs without a break.
class BootConfirmation {
 public:
  /// \brief Called from the main loop; true exactly once, when to confirm.
  bool poll(bool usb_configured, std::uint64_t now_us) {
    if (confirmed_) return false;
    if (!usb_configured) {
      configured_ = false;
      return false;
    }
    if (!configured_) {
      configured_ = true;
      since_us_ = now_us;
    }
    if (now_us - since_us_ < std::uint64_t{kConfirmAfterConfiguredMs} * 1000) return false;
    confirmed_ = true;
    return true;
  }
  bool confirmed() const { return confirmed_; }

 private:
  bool confirmed_ = false;
  bool configured_ = false;
  std::uint64_t since_us_ = 0;
};

}  // namespace flutterscan::firmware
