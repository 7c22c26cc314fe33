#pragma once
// The USB DFU 1.1 contract between the controller and the host flasher
// (Device Firmware Upgrade class specification 1.1; docs/protocol.md,
// "Firmware update"): class requests, states, status codes, the GETSTATUS
// reply, and the numbers both sides rely on (interface class codes, block
// size, detach timeout). The firmware's DFU runtime and DFU mode interfaces
// answer with these; host/device/dfu_flasher asks with them. Plain DFU, not
// DfuSe. Freestanding C++20: no heap, no exceptions.

#include <cstddef>
#include <cstdint>
#include <span>

namespace flutterscan::protocol {

/// \brief DFU class requests, bRequest (DFU 1.1 table 3.2).
enum class DfuRequest : std::uint8_t {
  kDetach = 0,
  kDnload = 1,
  kUpload = 2,
  kGetStatus = 3,
  kClrStatus = 4,
  kGetState = 5,
  kAbort = 6,
};

/// \brief bState (DFU 1.1 6.1.2).
enum class DfuState : std::uint8_t {
  kAppIdle = 0,
  kAppDetach = 1,
  kDfuIdle = 2,
  kDnloadSync = 3,
  kDnBusy = 4,
  kDnloadIdle = 5,
  kManifestSync = 6,
  kManifest = 7,
  kManifestWaitReset = 8,
  kUploadIdle = 9,
  kError = 10,
};

/// \brief bStatus (DFU 1.1 6.1.2).
enum class DfuStatus : std::uint8_t {
  kOk = 0x00,
  kErrTarget = 0x01,
  kErrFile = 0x02,
  kErrWrite = 0x03,
  kErrErase = 0x04,
  kErrCheckErased = 0x05,
  kErrProg = 0x06,
  kErrVerify = 0x07,
  kErrAddress = 0x08,
  kErrNotDone = 0x09,
  kErrFirmware = 0x0A,
  kErrVendor = 0x0B,
  kErrUsbReset = 0x0C,
  kErrPowerOnReset = 0x0D,
  kErrUnknown = 0x0E,
  kErrStalledPacket = 0x0F,
};

/// bmRequestType of DFU class requests to an interface (USB 2.0 9.3.1).
inline constexpr std::uint8_t kDfuRequestOut = 0x21;
inline constexpr std::uint8_t kDfuRequestIn = 0xA1;

/// The DFU interfaces (DFU 1.1 4.2.1, 4.2.3): class "application specific",
/// subclass DFU; protocol 1 on the application (runtime), 2 on the bootloader (DFU mode).
inline constexpr std::uint8_t kDfuInterfaceClass = 0xFE;
inline constexpr std::uint8_t kDfuInterfaceSubclass = 0x01;
inline constexpr std::uint8_t kDfuProtocolRuntime = 0x01;
inline constexpr std::uint8_t kDfuProtocolDfuMode = 0x02;

/// DFU functional descriptor (DFU 1.1 4.1.3), both images: bmAttributes
/// bitCanDnload | bitCanUpload | bitManifestationTolerant | bitWillDetach.
inline constexpr std::uint8_t kDfuAttributes = 0x0F;
/// wDetachTimeOut, ms: also DFU_DETACH's wValue from the host.
inline constexpr std::uint16_t kDfuDetachTimeoutMs = 1000;
/// wTransferSize: bytes per DNLOAD/UPLOAD block; block n is the image's bytes from n x this.
inline constexpr std::uint16_t kDfuTransferSize = 1024;
/// bcdDFUVersion: DFU 1.1.
inline constexpr std::uint16_t kBcdDfu = 0x0110;

/// Bytes of the DFU_GETSTATUS reply.
inline constexpr std::size_t kDfuStatusSize = 6;

/// \brief The DFU_GETSTATUS reply (DFU 1.1 6.1.2), decoded.
struct DfuStatusReply {
  DfuStatus status = DfuStatus::kOk;  ///< bStatus (a value outside the enum stays as sent)
  std::uint32_t poll_timeout_ms = 0;  ///< bwPollTimeout (24 bits)
  DfuState state = DfuState::kDfuIdle;
};

/// \brief Writes the 6-byte DFU_GETSTATUS reply into `out` (at least kDfuStatusSize bytes).
constexpr void write_dfu_status(std::span<std::uint8_t> out, DfuStatus status,
                                std::uint32_t poll_timeout_ms, DfuState state) {
  out[0] = static_cast<std::uint8_t>(status);
  out[1] = static_cast<std::uint8_t>(poll_timeout_ms & 0xFF);
  out[2] = static_cast<std::uint8_t>((poll_timeout_ms >> 8) & 0xFF);
  out[3] = static_cast<std::uint8_t>((poll_timeout_ms >> 16) & 0xFF);
  out[4] = static_cast<std::uint8_t>(state);
  out[5] = 0;  // iString
}

/// \brief The DFU_GETSTATUS reply in `bytes` (exactly kDfuStatusSize of them).
constexpr DfuStatusReply parse_dfu_status(std::span<const std::uint8_t, kDfuStatusSize> bytes) {
  return DfuStatusReply{
      static_cast<DfuStatus>(bytes[0]),
      static_cast<std::uint32_t>(bytes[1] | bytes[2] << 8 | bytes[3] << 16),
      static_cast<DfuState>(bytes[4]),
  };
}

}  // namespace flutterscan::protocol
