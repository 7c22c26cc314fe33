#pragma once
// The Transport seam (docs/devices.md): how the controller client reaches a
// controller. Reports are the protocol's 64-byte HID reports: requests go out,
// replies and exposure events come back on one IN stream. Backends: hidapi
// (hidapi_transport.hpp) and in-process to a VirtualController
// (in_process_transport.hpp).
//
// write_report and read_report may be called from two threads at once (the
// client's command path writes while its reader thread reads).

#include <array>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>

#include "device/device_error.hpp"
#include "flutterscan/common/protocol.hpp"

namespace flutterscan::device {

/// \brief One 64-byte HID report.
using Report = std::array<std::uint8_t, protocol::kReportSize>;

/// \brief A link to one controller.
class Transport {
 public:
  virtual ~Transport() = default;
  /// \brief Sends one request report (at most 64 bytes; shorter ones are zero-padded by
  /// the backend). kGone if the device is no longer there.
  virtual Expected<Done> write_report(std::span<const std::uint8_t> report) = 0;
  /// \brief The next IN report, waiting at most `timeout`; an empty optional if none
  /// came in time; kGone if the device went away. Never relies on the OS blocking
  /// (under umockdev reads return at once): waits with a deadline and short sleeps.
  virtual Expected<std::optional<Report>> read_report(std::chrono::milliseconds timeout) = 0;
  /// \brief Releases the device; later calls fail with kGone.
  virtual void close() = 0;
  /// \brief Human-readable link name (e.g. the hidraw path, "virtual controller").
  virtual std::string description() const = 0;
};

/// \brief Opens (or re-opens, after an unplug) the link to one controller.
using TransportOpener = std::function<Expected<std::unique_ptr<Transport>>()>;

}  // namespace flutterscan::device
