#pragma once
// USB DFU 1.1 vocabulary (Device Firmware Upgrade class specification 1.1):
// class requests, states, status codes, and the DFU_GETSTATUS reply. Shared
// by the application's DFU runtime interface and the bootloader's DFU mode.
// Freestanding C++20: no heap, no exceptions, no RTTI.

#include <cstddef>
#include <cstdint>
#include <span>

namespace flutterscan::firmware::usb {

/// \brief DFU class requests (DFU 1.1 table 3.2).
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

/// bmRequestType of DFU requests to an interface.
inline constexpr std::uint8_t kDfuRequestOut = 0x21;
inline constexpr std::uint8_t kDfuRequestIn = 0xA1;
/// Bytes of the DFU_GETSTATUS reply.
inline constexpr std::size_t kDfuStatusSize = 6;

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

}  // namespace flutterscan::firmware::usb
