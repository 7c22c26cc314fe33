#include "mock_usb_bus.hpp"

#include <cstdio>
#include <iostream>
#include <sstream>

namespace flutterscan::hil {

namespace {

/// The host controller and port the board is plugged into (bus 1, port 1).
constexpr const char* kUsbDeviceSyspath = "/devices/pci0000:00/0000:00:14.0/usb1/1-1";
constexpr int kBusNumber = 1;

std::string hex_bytes(std::span<const std::uint8_t> bytes) {
  std::string out;
  char b[3];
  for (std::uint8_t v : bytes) {
    std::snprintf(b, sizeof b, "%02x", v);
    out += b;
  }
  return out;
}

std::string hex4(unsigned v) {
  char b[8];
  std::snprintf(b, sizeof b, "%04x", v & 0xFFFF);
  return b;
}

std::string hex2(unsigned v) {
  char b[4];
  std::snprintf(b, sizeof b, "%02x", v & 0xFF);
  return b;
}

std::string upper_hex4(unsigned v) {
  char b[8];
  std::snprintf(b, sizeof b, "%04X", v & 0xFFFF);
  return b;
}

/// An interface of the configuration descriptor.
struct InterfaceInfo {
  int number, cls, subclass, protocol, endpoints;
};

std::vector<InterfaceInfo> interfaces_of(std::span<const std::uint8_t> config) {
  std::vector<InterfaceInfo> out;
  for (std::size_t i = 0; i + 1 < config.size() && config[i] >= 2; i += config[i])
    if (config[i + 1] == 4 && i + 8 < config.size() && config[i + 3] == 0)
      out.push_back({config[i + 2], config[i + 5], config[i + 6], config[i + 7], config[i + 4]});
  return out;
}

}  // namespace

MockUsbBus::MockUsbBus(BoardHost& host) : host_(host), testbed_(umockdev_testbed_new()) {}

MockUsbBus::~MockUsbBus() {
  if (testbed_ != nullptr) g_object_unref(testbed_);
}

bool MockUsbBus::sync() {
  const std::optional<int> wanted = host_.wanted_generation();
  if (present_ && (!wanted || *wanted != present_->generation)) remove();
  if (wanted && !present_) return add(*wanted);
  return true;
}

void MockUsbBus::remove() {
  for (const std::string& path : present_->syspaths)
    umockdev_testbed_remove_device(testbed_, ("/sys" + path).c_str());
  host_.removed(present_->generation);
  present_.reset();
}

bool MockUsbBus::add(int /*wanted*/) {
  const int devnum = next_devnum_++;
  char node[32];
  std::snprintf(node, sizeof node, "/dev/bus/usb/%03d/%03d", kBusNumber, devnum);
  const EnumeratedDevice d = host_.enumerate(static_cast<std::uint8_t>(devnum), node);
  const auto& e = d.enumeration;
  if (!e.ok) {
    std::cerr << "hil_harness: enumeration failed: " << e.error << "\n";
    return false;
  }
  Present p;
  p.generation = d.generation;

  // The usbdevfs node's handler first, so the node is served when it appears.
  auto usb = std::make_unique<UsbdevfsHandler>(host_, d.generation, node);
  GError* error = nullptr;
  if (!umockdev_testbed_attach_ioctl(testbed_, node, usb->ioctl_base(), &error)) {
    std::cerr << "hil_harness: attach_ioctl " << node << ": " << (error ? error->message : "failed")
              << "\n";
    g_clear_error(&error);
    return false;
  }
  const auto interfaces = interfaces_of(e.configuration_descriptor);
  const std::uint8_t configuration_value =
      e.configuration_descriptor.size() > 5 ? e.configuration_descriptor[5] : 1;
  std::ostringstream rec;
  rec << "P: " << kUsbDeviceSyspath << "\n"
      << "N: " << (node + 5) << "\n"
      << "E: SUBSYSTEM=usb\nE: DEVTYPE=usb_device\nE: DRIVER=usb\n"
      << "E: DEVNAME=" << node << "\n"
      << "E: BUSNUM=" << std::string(node + 13, 3) << "\n"
      << "E: DEVNUM=" << std::string(node + 17, 3) << "\n"
      << "E: PRODUCT=" << std::hex << d.vendor_id << "/" << d.product_id << "/" << d.bcd_device
      << std::dec << "\n"
      << "A: busnum=" << kBusNumber << "\\n\n"
      << "A: devnum=" << devnum << "\\n\n"
      << "A: idVendor=" << hex4(d.vendor_id) << "\\n\n"
      << "A: idProduct=" << hex4(d.product_id) << "\\n\n"
      << "A: bcdDevice=" << hex4(d.bcd_device) << "\\n\n"
      << "A: manufacturer=" << e.manufacturer << "\\n\n"
      << "A: product=" << e.product << "\\n\n"
      << "A: serial=" << e.serial << "\\n\n"
      << "A: speed=12\\n\n"
      << "A: version= 2.00\\n\n"
      << "A: bDeviceClass=00\\n\n"
      << "A: bMaxPacketSize0=" << int{e.device_descriptor[7]} << "\\n\n"
      << "A: bNumConfigurations=1\\n\n"
      << "A: bConfigurationValue=" << int{configuration_value} << "\\n\n"
      << "A: bNumInterfaces=" << (interfaces.size() < 10 ? " " : "") << interfaces.size() << "\\n\n"
      << "H: descriptors=" << hex_bytes(d.sysfs_descriptors) << "\n";
  if (!umockdev_testbed_add_from_string(testbed_, rec.str().c_str(), &error)) {
    std::cerr << "hil_harness: adding the USB device: " << (error ? error->message : "failed")
              << "\n";
    g_clear_error(&error);
    return false;
  }
  std::vector<std::string> paths{kUsbDeviceSyspath};

  std::optional<std::string> hid_interface_path;
  for (const InterfaceInfo& i : interfaces) {
    const std::string path = std::string(kUsbDeviceSyspath) +
                             "/1-1:" + std::to_string(configuration_value) + "." +
                             std::to_string(i.number);
    std::ostringstream r;
    r << "P: " << path << "\n"
      << "E: SUBSYSTEM=usb\nE: DEVTYPE=usb_interface\n"
      << (i.cls == 3 ? "E: DRIVER=usbhid\n" : "") << "E: INTERFACE=" << i.cls << "/" << i.subclass
      << "/" << i.protocol << "\n"
      << "A: bInterfaceNumber=" << hex2(static_cast<unsigned>(i.number)) << "\\n\n"
      << "A: bAlternateSetting= 0\\n\n"
      << "A: bInterfaceClass=" << hex2(static_cast<unsigned>(i.cls)) << "\\n\n"
      << "A: bInterfaceSubClass=" << hex2(static_cast<unsigned>(i.subclass)) << "\\n\n"
      << "A: bInterfaceProtocol=" << hex2(static_cast<unsigned>(i.protocol)) << "\\n\n"
      << "A: bNumEndpoints=" << hex2(static_cast<unsigned>(i.endpoints)) << "\\n\n";
    if (!umockdev_testbed_add_from_string(testbed_, r.str().c_str(), &error)) {
      std::cerr << "hil_harness: adding interface " << i.number << ": "
                << (error ? error->message : "failed") << "\n";
      g_clear_error(&error);
      return false;
    }
    paths.insert(paths.begin(), path);
    if (i.cls == 3 && !hid_interface_path) hid_interface_path = path;
  }

  if (hid_interface_path && !d.hid_report_descriptor.empty()) {
    // usbhid's HID device and its hidraw node (the kernel numbers HID devices
    // from 1 and hidraw nodes from 0).
    const int hid_number = next_hidraw_ + 1;
    char hid_name[32];
    std::snprintf(hid_name, sizeof hid_name, "0003:%s:%s.%04X", upper_hex4(d.vendor_id).c_str(),
                  upper_hex4(d.product_id).c_str(), hid_number);
    const std::string hid_path = *hid_interface_path + "/" + hid_name;
    const std::string hidraw_name = "hidraw" + std::to_string(next_hidraw_++);
    const std::string hidraw_node = "/dev/" + hidraw_name;
    const std::string hid_title = e.manufacturer + " " + e.product;

    HidrawIdentity identity;
    identity.vendor_id = d.vendor_id;
    identity.product_id = d.product_id;
    identity.name = hid_title;
    identity.phys = "usb-0000:00:14.0-1/input0";
    identity.uniq = e.serial;
    identity.report_descriptor = d.hid_report_descriptor;
    auto hidraw = std::make_unique<HidrawHandler>(host_, d.generation, identity);
    if (!umockdev_testbed_attach_ioctl(testbed_, hidraw_node.c_str(), hidraw->ioctl_base(),
                                       &error)) {
      std::cerr << "hil_harness: attach_ioctl " << hidraw_node << ": "
                << (error ? error->message : "failed") << "\n";
      g_clear_error(&error);
      return false;
    }
    char hid_id[64];
    std::snprintf(hid_id, sizeof hid_id, "0003:0000%s:0000%s", upper_hex4(d.vendor_id).c_str(),
                  upper_hex4(d.product_id).c_str());
    std::ostringstream r;
    r << "P: " << hid_path << "\n"
      << "E: SUBSYSTEM=hid\nE: DRIVER=hid-generic\n"
      << "E: HID_ID=" << hid_id << "\n"
      << "E: HID_NAME=" << hid_title << "\n"
      << "E: HID_PHYS=" << identity.phys << "\n"
      << "E: HID_UNIQ=" << e.serial << "\n"
      << "E: MODALIAS=hid:b0003g0001v0000" << upper_hex4(d.vendor_id) << "p0000"
      << upper_hex4(d.product_id) << "\n"
      << "H: report_descriptor=" << hex_bytes(d.hid_report_descriptor) << "\n"
      << "\n"
      << "P: " << hid_path << "/hidraw/" << hidraw_name << "\n"
      << "N: " << hidraw_name << "=00\n"
      << "E: SUBSYSTEM=hidraw\n"
      << "E: DEVNAME=" << hidraw_node << "\n"
      << "L: device=../../../" << hid_name << "\n";
    if (!umockdev_testbed_add_from_string(testbed_, r.str().c_str(), &error)) {
      std::cerr << "hil_harness: adding the HID device: " << (error ? error->message : "failed")
                << "\n";
      g_clear_error(&error);
      return false;
    }
    paths.insert(paths.begin(), hid_path);
    paths.insert(paths.begin(), hid_path + "/hidraw/" + hidraw_name);
    hidraw_handlers_.push_back(std::move(hidraw));
  }
  usb_handlers_.push_back(std::move(usb));
  p.syspaths = std::move(paths);
  present_ = std::move(p);
  return true;
}

}  // namespace flutterscan::hil
