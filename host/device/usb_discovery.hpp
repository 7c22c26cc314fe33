#pragma once
// Finding controllers on USB: application-mode ones through hidapi (VID 0x1209,
// PID 0x0001), DFU-mode ones (PID 0x0002) through libusb, each with its serial
// number (24 hex digits of the STM32 unique ID; the same in both modes).

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "device/device_error.hpp"
#include "device/transport.hpp"

namespace flutterscan::device {

/// \brief Which firmware answers on the USB side.
enum class DeviceMode { kApplication, kBootloader };

/// \brief One controller seen on USB.
struct FoundDevice {
  DeviceMode mode = DeviceMode::kApplication;
  std::string serial;         ///< empty if it could not be read
  std::string hid_path;       ///< application mode: hidapi path
  int bus = -1;               ///< libusb bus number (bootloader mode)
  int address = -1;           ///< libusb device address (bootloader mode)
  std::uint16_t release = 0;  ///< bcdDevice
  std::string product;        ///< product string
  std::string problem;        ///< why something could not be read (e.g. permissions), else empty
};

/// \brief "application" or "DFU bootloader".
const char* mode_name(DeviceMode mode);

/// \brief Every controller connected now, application mode first. Fails only if
/// USB cannot be enumerated at all.
Expected<std::vector<FoundDevice>> find_controllers();

/// \brief The one controller in `mode` named by `serial` or, without a serial,
/// the only one. kNotFound if none; kAmbiguous (message lists them) if several
/// and none named.
Expected<FoundDevice> pick_controller(const std::vector<FoundDevice>& found,
                                      const std::optional<std::string>& serial, DeviceMode mode);

/// \brief "  SERIAL  application  flutterscan LED controller" lines, one per device.
std::string describe_devices(const std::vector<FoundDevice>& found);

/// \brief Opens (and after an unplug re-opens) the application-mode controller
/// with serial number `serial` through hidapi.
TransportOpener hid_opener(std::string serial);

}  // namespace flutterscan::device
