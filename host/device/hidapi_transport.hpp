#pragma once
// Transport over hidapi. The library is built twice (CMake): against
// libhidapi-hidraw for the product binary, and against libhidapi-libusb so the
// HIL tests can check both backends.

#include <shared_mutex>
#include <string>

#include "device/transport.hpp"

struct hid_device_;

namespace flutterscan::device {

/// \brief A Transport on one hidapi device.
class HidapiTransport final : public Transport {
 public:
  /// \brief Opens the device at hidapi `path` (from discovery); kAccess or kGone on failure.
  static Expected<std::unique_ptr<Transport>> open(const std::string& path,
                                                   const std::string& serial);
  ~HidapiTransport() override;

  Expected<Done> write_report(std::span<const std::uint8_t> report) override;
  Expected<std::optional<Report>> read_report(std::chrono::milliseconds timeout) override;
  void close() override;
  std::string description() const override;

 private:
  HidapiTransport(hid_device_* device, std::string path, std::string serial);
  hid_device_* device_;
  std::string path_;
  std::string serial_;
  /// Reads and writes hold it shared around each hidapi call; close() exclusively,
  /// so the device is never freed under a call on another thread.
  std::shared_mutex use_mutex_;
  bool closed_ = false;
};

}  // namespace flutterscan::device
