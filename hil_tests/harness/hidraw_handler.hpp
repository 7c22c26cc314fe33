#pragma once
// /dev/hidrawN emulated on a DevicePort, the way the kernel's usbhid + hidraw
// present the application's HID interface: write() of [report id 0][64 bytes]
// becomes one interrupt OUT packet, read() returns the next interrupt IN packet
// (EAGAIN when none is waiting: emulated nodes are regular files, so poll()
// always says readable), and the HIDIOCGRDESCSIZE / HIDIOCGRDESC /
// HIDIOCGRAWINFO / HIDIOCGRAWNAME / HIDIOCGRAWPHYS / HIDIOCGRAWUNIQ ioctls.
// Runs on umockdev's worker thread.

#include <umockdev.h>

#include <cstdint>
#include <string>
#include <vector>

#include "device_port.hpp"
#include "flutterscan/firmware/usb/usb_descriptors.hpp"

namespace flutterscan::hil {

/// \brief Identity the hidraw ioctls report.
struct HidrawIdentity {
  std::uint16_t vendor_id = 0;
  std::uint16_t product_id = 0;
  std::string name;  ///< "manufacturer product"
  std::string phys;
  std::string uniq;  ///< serial number
  std::vector<std::uint8_t> report_descriptor;
  std::uint8_t in_endpoint = firmware::usb::kHidInEndpoint.address;  ///< the firmware's own
  std::uint8_t out_endpoint = firmware::usb::kHidOutEndpoint.address;
};

/// \brief The read/write/ioctl handler of one hidraw node.
class HidrawHandler {
 public:
  HidrawHandler(DevicePort& port, int generation, HidrawIdentity identity);
  ~HidrawHandler();
  HidrawHandler(const HidrawHandler&) = delete;
  HidrawHandler& operator=(const HidrawHandler&) = delete;

  UMockdevIoctlBase* ioctl_base() const { return base_; }

 private:
  static gboolean on_ioctl(UMockdevIoctlBase*, UMockdevIoctlClient* client, gpointer self);
  static gboolean on_read(UMockdevIoctlBase*, UMockdevIoctlClient* client, gpointer self);
  static gboolean on_write(UMockdevIoctlBase*, UMockdevIoctlClient* client, gpointer self);
  void handle_ioctl(UMockdevIoctlClient* client);
  void handle_read(UMockdevIoctlClient* client);
  void handle_write(UMockdevIoctlClient* client);

  DevicePort& port_;
  int generation_;
  HidrawIdentity identity_;
  UMockdevIoctlBase* base_;
};

}  // namespace flutterscan::hil
