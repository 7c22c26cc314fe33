#pragma once
// What the bootloader does at reset (docs/hardware.md, "Boot and recovery").
//
// It starts the application only if
// - the application did not ask for DFU mode (the hand-off word:
//   EnterBootloader, DFU_DETACH), and the boot pin is not held;
// - fewer than kMaxUnconfirmedStarts starts in a row went unconfirmed: the
//   application confirms itself (BootConfirmation) once a host command arrives
//   over configured USB, or once USB has stayed configured for
//   kConfirmAfterConfiguredMs, so an image that hangs before that (watchdog
//   resets) or never brings USB up falls back to DFU mode by itself;
// - fewer than kMaxWatchdogResets resets in a row were watchdog resets (RCC_CSR
//   IWDGRSTF/WWDGRSTF, read by the bootloader at reset): counted in the same
//   record, and confirmation does not clear it, so an image that confirms
//   itself and then hangs falls back to DFU mode too; any other reset (pin,
//   software, power-on) and a deliberate leave from DFU mode clear it;
// - the region holds an image the common checker accepts for this board AND
//   that the jump can use: load address = the region's, vector table exactly
//   at kAppVectorTableOffset (the address the bootloader jumps through, so the
//   image CRC covers it), initial SP inside SRAM, reset vector a Thumb address
//   inside the image (check_boot_image).
// Otherwise it stays in DFU mode, so an interrupted or bad flash can always be
// repeated. Freestanding C++20: no heap, no exceptions, no RTTI.

#include <bit>
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
/// Watchdog resets in a row after which the bootloader stays in DFU mode.
inline constexpr std::uint32_t kMaxWatchdogResets = kMaxUnconfirmedStarts;
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
  kRolledBack,         ///< security_version below the board's security floor
};

/// \brief Whether the bootloader can start the image in `region_bytes`: the
/// common checker, what the jump itself reads (see the file comment), and its
/// security_version against the board's `security_floor` (security_floor.hpp).
inline BootImageCheck check_boot_image(std::span<const std::uint8_t> region_bytes,
                                       const AppRegion& region, std::uint8_t security_floor = 0) {
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
  if (h.security_version < security_floor) return BootImageCheck::kRolledBack;
  return BootImageCheck::kOk;
}

/// \brief The record the bootloader and the application share across warm
/// resets (no-init SRAM after the hand-off word; random after power-on, which
/// the check word detects).
struct BootRecord {
  std::uint32_t magic;               ///< kBootRecordMagic
  std::uint32_t unconfirmed_starts;  ///< application starts since the last confirmation
  std::uint32_t watchdog_resets;     ///< watchdog resets in a row; confirmation keeps it
  std::uint32_t reset_flags;         ///< RCC_CSR's reset flags at this reset (the
                                     ///< bootloader clears them; the application's reset cause)
  std::uint32_t check;               ///< boot_record_check() of the fields above
};
/// Not the 12-byte record's 0xB0075EC0: a record of that layout reads as invalid.
inline constexpr std::uint32_t kBootRecordMagic = 0xB0075EC1;

/// \brief The check word of a record with these fields.
constexpr std::uint32_t boot_record_check(std::uint32_t magic, std::uint32_t starts,
                                          std::uint32_t watchdog_resets,
                                          std::uint32_t reset_flags) {
  return ~(magic ^ starts ^ std::rotl(watchdog_resets, 11) ^ std::rotl(reset_flags, 22));
}

/// \brief Whether `record` was written by make_boot_record (not power-on SRAM).
inline bool boot_record_valid(const BootRecord& record) {
  return record.magic == kBootRecordMagic &&
         record.check == boot_record_check(record.magic, record.unconfirmed_starts,
                                           record.watchdog_resets, record.reset_flags);
}

/// \brief Unconfirmed starts in `record`; 0 if it is not valid (power-on).
inline std::uint32_t unconfirmed_starts(const BootRecord& record) {
  return boot_record_valid(record) ? record.unconfirmed_starts : 0;
}

/// \brief Watchdog resets in a row in `record`; 0 if it is not valid (power-on).
inline std::uint32_t watchdog_resets(const BootRecord& record) {
  return boot_record_valid(record) ? record.watchdog_resets : 0;
}

/// \brief The reset flags the bootloader found at this reset; 0 if not valid.
inline std::uint32_t reset_flags(const BootRecord& record) {
  return boot_record_valid(record) ? record.reset_flags : 0;
}

/// \brief A valid record.
inline BootRecord make_boot_record(std::uint32_t starts, std::uint32_t watchdog_resets = 0,
                                   std::uint32_t reset_flags = 0) {
  return {kBootRecordMagic, starts, watchdog_resets, reset_flags,
          boot_record_check(kBootRecordMagic, starts, watchdog_resets, reset_flags)};
}

/// \brief What the application stores when it confirms itself: no unconfirmed
/// start, the watchdog count and the reset flags kept (only a reset that is not
/// a watchdog reset, or a deliberate leave from DFU mode, clears the count).
inline BootRecord confirm_boot_record(const BootRecord& record) {
  return make_boot_record(0, watchdog_resets(record), reset_flags(record));
}

/// \brief What the bootloader knows at reset.
struct BootInputs {
  bool dfu_requested = false;   ///< the application's hand-off word
  bool boot_pin_held = false;   ///< the recovery pin (docs/hardware.md)
  bool watchdog_reset = false;  ///< this reset was a watchdog's (RCC_CSR IWDGRSTF/WWDGRSTF)
  std::uint32_t unconfirmed_starts = 0;
  std::uint32_t watchdog_resets = 0;  ///< the record's: watchdog resets in a row before this one
  BootImageCheck image = BootImageCheck::kImageRefused;
};

/// \brief The decision, and the counts to store before acting on it.
struct BootDecision {
  BootTarget target = BootTarget::kDfuMode;
  std::uint32_t unconfirmed_starts = 0;
  std::uint32_t watchdog_resets = 0;
};

/// \brief The bootloader's decision at reset.
inline BootDecision decide_boot(const BootInputs& in) {
  // In a row: any other reset starts the count again (saturating, never wraps).
  const std::uint32_t watchdog =
      in.watchdog_reset
          ? (in.watchdog_resets < kMaxWatchdogResets ? in.watchdog_resets : kMaxWatchdogResets) + 1
          : 0;
  if (in.dfu_requested || in.boot_pin_held || in.image != BootImageCheck::kOk ||
      in.unconfirmed_starts >= kMaxUnconfirmedStarts || watchdog >= kMaxWatchdogResets)
    return {BootTarget::kDfuMode, in.unconfirmed_starts, watchdog};
  return {BootTarget::kApplication, in.unconfirmed_starts + 1, watchdog};  // on trial
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

/// \brief The application's side: confirms itself once a host says it works:
/// a query (GetInfo or GetStatus: CommandHandler::queries_answered) answered
/// while USB is configured confirms at once; otherwise USB configured (a host
/// enumerated it and kept it) for kConfirmAfterConfiguredMs without a break.
class BootConfirmation {
 public:
  /// \brief Called from the main loop after the USB work of each pass
  /// (`queries_answered`: the handler's count since this start); true exactly
  /// once, when to confirm.
  bool poll(bool usb_configured, std::uint32_t queries_answered, std::uint64_t now_us) {
    if (confirmed_) return false;
    if (!usb_configured) {
      configured_ = false;
      queries_seen_ = queries_answered;  // not over configured USB: does not count
      return false;
    }
    if (!configured_) {
      configured_ = true;
      since_us_ = now_us;
    }
    const bool host_query = queries_answered != queries_seen_;
    queries_seen_ = queries_answered;
    if (!host_query && now_us - since_us_ < std::uint64_t{kConfirmAfterConfiguredMs} * 1000)
      return false;
    confirmed_ = true;
    return true;
  }
  bool confirmed() const { return confirmed_; }

 private:
  bool confirmed_ = false;
  bool configured_ = false;
  std::uint32_t queries_seen_ = 0;
  std::uint64_t since_us_ = 0;
};

}  // namespace flutterscan::firmware
