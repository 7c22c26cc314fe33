#pragma once
// The USB DFU 1.1 vocabulary as the firmware's DFU runtime interface (the
// application) and DFU mode interface (the bootloader) name it: requests,
// states, status codes, the GETSTATUS reply. Defined once, for the firmware
// and the host flasher alike, in common/dfu.hpp; named here in the usb namespace.
// Freestanding C++20: no heap, no exceptions, no RTTI.

#include "flutterscan/common/dfu.hpp"

namespace flutterscan::firmware::usb {

using protocol::DfuRequest;
using protocol::DfuState;
using protocol::DfuStatus;
using protocol::kDfuRequestIn;
using protocol::kDfuRequestOut;
using protocol::kDfuStatusSize;
using protocol::kDfuTransferSize;
using protocol::write_dfu_status;

}  // namespace flutterscan::firmware::usb
