#pragma once
// Flashing a controller over USB DFU 1.1 (plain DFU, not DfuSe; the contract is
// in docs/protocol.md): detach the application (DFU_DETACH on its DFU runtime
// interface), wait for the bootloader (PID 0x0002, same serial number), then
// GETSTATUS / DNLOAD block by block (block n lands at the application base +
// n * 1024), a zero-length DNLOAD, manifest, read back with UPLOAD and compare,
// reset, wait for the application and check the version GetInfo reports.
// The DFU vocabulary is common/dfu.hpp, the firmware's too.
// The DFU request sequence is written against DfuControl so it is tested
// without USB; LibusbDfuControl is the real one.

#include <chrono>
#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "device/device_error.hpp"
#include "device/firmware_image.hpp"
#include "flutterscan/common/dfu.hpp"
#include "flutterscan/common/protocol.hpp"

namespace flutterscan::device {

using protocol::DfuRequest;
using protocol::DfuState;
using protocol::DfuStatusReply;

/// The longest the flasher waits on one bwPollTimeout (a sector erase takes under
/// 2 s): a device asking for more (up to 4.6 hours) is waited on this long.
inline constexpr std::chrono::milliseconds kMaxDfuPollSleep{5000};
/// The longest the flasher waits for one block (or the manifest) in all.
inline constexpr std::chrono::milliseconds kMaxDfuBusyWait{60'000};

/// \brief The DFU status code's name and meaning ("errFIRMWARE: firmware corrupt").
std::string dfu_status_text(std::uint8_t status);
/// \brief The DFU state's name ("dfuIDLE").
const char* dfu_state_name(DfuState state);

/// \brief Class requests to one DFU interface.
class DfuControl {
 public:
  virtual ~DfuControl() = default;
  /// \brief Host-to-device class request with `data`.
  virtual Expected<Done> control_out(DfuRequest request, std::uint16_t value,
                                     std::span<const std::uint8_t> data) = 0;
  /// \brief Device-to-host class request; at most `length` bytes come back.
  virtual Expected<std::vector<std::uint8_t>> control_in(DfuRequest request, std::uint16_t value,
                                                         std::uint16_t length) = 0;
};

/// \brief How long to wait between polls (injected so tests do not sleep).
using DfuSleeper = std::function<void(std::chrono::milliseconds)>;
/// \brief Progress: bytes done of total.
using ProgressCallback = std::function<void(std::size_t done, std::size_t total)>;

/// \brief GETSTATUS.
Expected<DfuStatusReply> dfu_get_status(DfuControl& dfu);
/// \brief Brings the bootloader to dfuIDLE (CLRSTATUS from dfuERROR, ABORT from others).
Expected<Done> dfu_make_idle(DfuControl& dfu);
/// \brief Downloads `image` block by block, the zero-length DNLOAD and manifest,
/// until dfuIDLE; kRejected naming the DFU status if the bootloader refuses.
Expected<Done> dfu_download(DfuControl& dfu, std::span<const std::uint8_t> image,
                            const ProgressCallback& progress, const DfuSleeper& sleep);
/// \brief Reads `length` bytes of the application region back with UPLOAD.
Expected<std::vector<std::uint8_t>> dfu_upload(DfuControl& dfu, std::size_t length);

/// \brief What flash_controller is told.
struct FlashOptions {
  /// The controller to flash; without it, the only controller connected.
  std::optional<std::string> serial;
  /// Longest wait for the bootloader or the application to enumerate.
  std::chrono::milliseconds enumerate_timeout{10'000};
  /// Progress of the download (bytes).
  ProgressCallback progress;
  /// One line per step ("detaching", "bootloader found", ...).
  std::function<void(const std::string&)> log;
};

/// \brief What a flash did.
struct FlashReport {
  std::string serial;
  std::optional<protocol::InfoReply> before;  ///< GetInfo before (none if it was in DFU mode)
  protocol::InfoReply after{};                ///< GetInfo of the new application
  double download_seconds = 0;
  double kib_per_second = 0;
};

/// \brief Flashes `image` (already loaded and checked) into one controller.
/// kBadInput if the controller reports another board than the image's.
Expected<FlashReport> flash_controller(const FirmwareImage& image, const FlashOptions& options);

}  // namespace flutterscan::device
