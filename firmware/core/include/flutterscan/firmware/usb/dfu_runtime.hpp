#pragma once
// The application's DFU runtime interface (interface 1; DFU 1.1 chapter 5):
// DFU_GETSTATUS and DFU_GETSTATE report appIDLE (appDETACH after a detach);
// DFU_DETACH is accepted and, once its status stage is done, the controller
// turns every LED off and the image resets into the bootloader
// (Controller::enter_bootloader, then Port::enter_bootloader from the main
// loop): bitWillDetach, the host only waits for the bootloader to enumerate.
// Every other request is answered with STALL.
// Freestanding C++20: no heap, no exceptions, no RTTI.

#include <cstdint>
#include <span>

#include "flutterscan/firmware/controller.hpp"
#include "flutterscan/firmware/usb/dfu.hpp"
#include "flutterscan/firmware/usb/usb_function.hpp"

namespace flutterscan::firmware::usb {

/// \brief The DFU runtime interface.
class DfuRuntime final : public UsbFunction {
 public:
  /// \brief The interface `interface_number` detaching through `controller`.
  DfuRuntime(Controller& controller, std::uint8_t interface_number)
      : controller_(controller), interface_number_(interface_number) {}

  DfuState state() const { return state_; }
  /// \brief A DFU_DETACH completed (the bootloader entry is under way).
  bool detached() const { return state_ == DfuState::kAppDetach; }

  // UsbFunction ------------------------------------------------------------
  ControlReply control_request(const SetupPacket& setup, std::span<std::uint8_t> buffer) override;
  void control_complete(const SetupPacket& setup) override;
  void set_configured(bool configured) override { (void)configured; }

 private:
  Controller& controller_;
  std::uint8_t interface_number_;
  DfuState state_ = DfuState::kAppIdle;
};

}  // namespace flutterscan::firmware::usb
