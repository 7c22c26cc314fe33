#pragma once
// The bootloader image's USB device: the device core with the bootloader's
// descriptors (VID 0x1209, PID kUsbProductIdBootloader, the same serial number
// as the application) and the DFU mode interface (interface 0) over the flash.
// A driver delivers its events here; the bootloader's loop starts the
// application once leave_requested().
// Freestanding C++20: no heap, no exceptions, no RTTI.

#include <cstdint>
#include <span>

#include "flutterscan/common/image_header.hpp"
#include "flutterscan/firmware/flash.hpp"
#include "flutterscan/firmware/usb/dfu_mode.hpp"
#include "flutterscan/firmware/usb/usb_descriptors.hpp"
#include "flutterscan/firmware/usb/usb_device.hpp"

namespace flutterscan::firmware::usb {

/// \brief DFU mode device of the bootloader.
class BootloaderUsb final : public UsbDeviceEvents {
 public:
  /// \brief The device on `controller` writing `region` of `flash`, refusing
  /// images below `floor`; `device_descriptor` (bootloader_device_descriptor())
  /// must outlive it.
  BootloaderUsb(UsbDeviceController& controller, Flash& flash, SecurityFloor& floor,
                const FlashLayout& layout, const AppRegion& region,
                std::span<const std::uint8_t> device_descriptor,
                std::span<const std::uint8_t, kUniqueIdSize> unique_id)
      : descriptors_(bootloader_descriptors(device_descriptor)),
        device_(controller, descriptors_, unique_id),
        dfu_(flash, floor, layout, region, kDfuModeInterface) {
    device_.set_function(kDfuModeInterface, &dfu_);
  }
  BootloaderUsb(const BootloaderUsb&) = delete;
  BootloaderUsb& operator=(const BootloaderUsb&) = delete;

  /// \brief Time to start the application (DfuMode::leave_requested()).
  bool leave_requested() const { return dfu_.leave_requested(); }
  UsbDevice& device() { return device_; }
  DfuMode& dfu() { return dfu_; }

  // UsbDeviceEvents --------------------------------------------------------
  void on_bus_reset() override { device_.on_bus_reset(); }
  void on_setup(const SetupPacket& setup) override { device_.on_setup(setup); }
  void on_ep0_out_complete(std::size_t received) override { device_.on_ep0_out_complete(received); }
  void on_ep0_status_complete() override { device_.on_ep0_status_complete(); }
  void on_out_packet(std::uint8_t address, std::span<const std::uint8_t> packet) override {
    device_.on_out_packet(address, packet);
  }
  void on_in_complete(std::uint8_t address) override { device_.on_in_complete(address); }

 private:
  UsbDescriptorSet descriptors_;
  UsbDevice device_;
  DfuMode dfu_;
};

}  // namespace flutterscan::firmware::usb
