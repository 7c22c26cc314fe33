#include "flutterscan/firmware/usb/dfu_runtime.hpp"

namespace flutterscan::firmware::usb {

ControlReply DfuRuntime::control_request(const SetupPacket& setup, std::span<std::uint8_t> buffer) {
  if (setup.index != interface_number_) return ControlReply::stall();
  switch (static_cast<DfuRequest>(setup.request)) {
    case DfuRequest::kDetach:
      // wValue: the host's detach timeout; this device detaches at once.
      if (setup.request_type != kDfuRequestOut || setup.length != 0) return ControlReply::stall();
      return ControlReply::status();
    case DfuRequest::kGetStatus:
      if (setup.request_type != kDfuRequestIn || setup.value != 0 || setup.length == 0 ||
          buffer.size() < kDfuStatusSize)
        return ControlReply::stall();
      write_dfu_status(buffer, DfuStatus::kOk, 0, state_);
      return ControlReply::send(kDfuStatusSize);
    case DfuRequest::kGetState:
      if (setup.request_type != kDfuRequestIn || setup.value != 0 || setup.length == 0 ||
          buffer.empty())
        return ControlReply::stall();
      buffer[0] = static_cast<std::uint8_t>(state_);
      return ControlReply::send(1);
    default:
      return ControlReply::stall();  // DNLOAD, UPLOAD, CLRSTATUS, ABORT: DFU mode only
  }
}

void DfuRuntime::control_complete(const SetupPacket& setup) {
  if (setup.request != static_cast<std::uint8_t>(DfuRequest::kDetach)) return;
  state_ = DfuState::kAppDetach;
  // Disarms (every LED off); the main loop's Controller::poll() then calls
  // Port::enter_bootloader().
  controller_.enter_bootloader(protocol::EnterBootloaderRequest{protocol::kEnterBootloaderMagic});
}

}  // namespace flutterscan::firmware::usb
