#include "flutterscan/firmware/usb/application_usb.hpp"

namespace flutterscan::firmware::usb {

ApplicationUsb::ApplicationUsb(UsbDeviceController& controller, Controller& core,
                               CommandHandler& handler,
                               std::span<const std::uint8_t> device_descriptor,
                               std::span<const std::uint8_t, kUniqueIdSize> unique_id)
    : core_(core),
      descriptors_(application_descriptors(device_descriptor)),
      device_(controller, descriptors_, unique_id),
      hid_(controller, handler, kHidInEndpoint.address, kHidOutEndpoint.address, kHidInterface),
      dfu_(core, kDfuRuntimeInterface) {
  device_.set_function(kHidInterface, &hid_);
  device_.set_function(kDfuRuntimeInterface, &dfu_);
}

void ApplicationUsb::poll() {
  hid_.poll();
  // The EnterBootloader reply goes out before the reset, unless the host
  // does not read it for kBootloaderReplyWaitPolls passes.
  bool may_enter_bootloader = true;
  if (core_.bootloader_requested() && hid_.replies_pending() &&
      bootloader_wait_polls_ < kBootloaderReplyWaitPolls) {
    ++bootloader_wait_polls_;
    may_enter_bootloader = false;
  }
  core_.poll(may_enter_bootloader);
}

void ApplicationUsb::on_bus_reset() {
  device_.on_bus_reset();
  core_.on_usb_reset();
}

}  // namespace flutterscan::firmware::usb
