#pragma once
// The application image's USB device: the device core with the application's
// descriptors (VID 0x1209, PID kUsbProductIdApplication), the HID command and
// event interface (interface 0) and the DFU runtime interface (interface 1).
// A driver delivers its events here (this is the UsbDeviceEvents it calls);
// the main loop calls poll(). A USB bus reset also disarms the controller
// (every LED off) and drops an unfinished code upload.
// Freestanding C++20: no heap, no exceptions, no RTTI.

#include <cstdint>
#include <span>

#include "flutterscan/firmware/command_handler.hpp"
#include "flutterscan/firmware/controller.hpp"
#include "flutterscan/firmware/usb/dfu_runtime.hpp"
#include "flutterscan/firmware/usb/hid_interface.hpp"
#include "flutterscan/firmware/usb/usb_descriptors.hpp"
#include "flutterscan/firmware/usb/usb_device.hpp"

namespace flutterscan::firmware::usb {

/// Main-loop passes an accepted EnterBootloader waits for its reply to be read
/// before the bootloader is entered anyway (at 1 kHz: 0.2 s).
inline constexpr int kBootloaderReplyWaitPolls = 200;

/// \brief HID + DFU runtime device of the application.
class ApplicationUsb final : public UsbDeviceEvents {
 public:
  /// \brief The device on `controller`, serving `core` through `handler`;
  /// `device_descriptor` (application_device_descriptor()) must outlive it.
  ApplicationUsb(UsbDeviceController& controller, Controller& core, CommandHandler& handler,
                 std::span<const std::uint8_t> device_descriptor,
                 std::span<const std::uint8_t, kUniqueIdSize> unique_id);
  ApplicationUsb(const ApplicationUsb&) = delete;
  ApplicationUsb& operator=(const ApplicationUsb&) = delete;

  /// \brief Main-loop work: HID requests, replies and events; Controller::poll()
  /// (watchdog, bootloader entry once the EnterBootloader reply was read).
  void poll();

  UsbDevice& device() { return device_; }
  HidInterface& hid() { return hid_; }
  DfuRuntime& dfu_runtime() { return dfu_; }

  // UsbDeviceEvents --------------------------------------------------------
  void on_bus_reset() override;
  void on_setup(const SetupPacket& setup) override { device_.on_setup(setup); }
  void on_ep0_out_complete(std::size_t received) override { device_.on_ep0_out_complete(received); }
  void on_ep0_status_complete() override { device_.on_ep0_status_complete(); }
  void on_out_packet(std::uint8_t address, std::span<const std::uint8_t> packet) override {
    device_.on_out_packet(address, packet);
  }
  void on_in_complete(std::uint8_t address) override { device_.on_in_complete(address); }

 private:
  Controller& core_;
  UsbDescriptorSet descriptors_;
  UsbDevice device_;
  HidInterface hid_;
  DfuRuntime dfu_;
  int bootloader_wait_polls_ = 0;
};

}  // namespace flutterscan::firmware::usb
