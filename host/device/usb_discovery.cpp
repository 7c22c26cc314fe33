#include "device/usb_discovery.hpp"

#include <hidapi.h>
#include <libusb.h>

#include <algorithm>
#include <cstdio>

#include "device/hidapi_transport.hpp"
#include "flutterscan/common/protocol.hpp"

namespace flutterscan::device {

namespace {

std::string narrow(const wchar_t* text) {
  std::string out;
  if (text == nullptr) return out;
  for (; *text != 0; ++text) out += *text < 128 ? static_cast<char>(*text) : '?';
  return out;
}

std::vector<FoundDevice> find_application_devices() {
  static const int init = hid_init();
  (void)init;
  std::vector<FoundDevice> found;
  hid_device_info* list = hid_enumerate(protocol::kUsbVendorId, protocol::kUsbProductIdApplication);
  for (hid_device_info* info = list; info != nullptr; info = info->next) {
    // One HID interface per controller: interface 0 (the DFU runtime is not HID).
    if (info->interface_number > 0) continue;
    FoundDevice device;
    device.mode = DeviceMode::kApplication;
    device.serial = narrow(info->serial_number);
    device.hid_path = info->path != nullptr ? info->path : "";
    device.release = info->release_number;
    device.product = narrow(info->product_string);
    if (device.serial.empty()) device.problem = "serial number not readable";
    found.push_back(device);
  }
  hid_free_enumeration(list);
  return found;
}

Expected<std::vector<FoundDevice>> find_bootloader_devices() {
  using Out = Expected<std::vector<FoundDevice>>;
  libusb_context* context = nullptr;
  if (const int rc = libusb_init(&context); rc != 0)
    return fail<std::vector<FoundDevice>>(
        ErrorKind::kAccess, std::string("libusb cannot start: ") + libusb_strerror(rc));
  std::vector<FoundDevice> found;
  libusb_device** list = nullptr;
  const ssize_t count = libusb_get_device_list(context, &list);
  for (ssize_t i = 0; i < count; ++i) {
    libusb_device_descriptor descriptor{};
    if (libusb_get_device_descriptor(list[i], &descriptor) != 0) continue;
    if (descriptor.idVendor != protocol::kUsbVendorId ||
        descriptor.idProduct != protocol::kUsbProductIdBootloader)
      continue;
    FoundDevice device;
    device.mode = DeviceMode::kBootloader;
    device.bus = libusb_get_bus_number(list[i]);
    device.address = libusb_get_device_address(list[i]);
    device.release = descriptor.bcdDevice;
    libusb_device_handle* handle = nullptr;
    if (const int rc = libusb_open(list[i], &handle); rc == 0) {
      unsigned char text[128];
      if (descriptor.iSerialNumber != 0 &&
          libusb_get_string_descriptor_ascii(handle, descriptor.iSerialNumber, text, sizeof text) >
              0)
        device.serial = reinterpret_cast<const char*>(text);
      if (descriptor.iProduct != 0 &&
          libusb_get_string_descriptor_ascii(handle, descriptor.iProduct, text, sizeof text) > 0)
        device.product = reinterpret_cast<const char*>(text);
      libusb_close(handle);
    } else {
      device.problem = std::string("cannot open (") + libusb_strerror(rc) +
                       "): is the udev rule installed and are you in the plugdev group?";
    }
    found.push_back(device);
  }
  if (count >= 0) libusb_free_device_list(list, 1);  // an empty list is allocated too
  libusb_exit(context);
  return Out::success(found);
}

}  // namespace

const char* mode_name(DeviceMode mode) {
  return mode == DeviceMode::kApplication ? "application" : "DFU bootloader";
}

Expected<std::vector<FoundDevice>> find_controllers() {
  std::vector<FoundDevice> found = find_application_devices();
  auto bootloaders = find_bootloader_devices();
  if (!bootloaders.ok()) return fail<std::vector<FoundDevice>>(bootloaders.error());
  found.insert(found.end(), bootloaders.value().begin(), bootloaders.value().end());
  return Expected<std::vector<FoundDevice>>::success(found);
}

std::string describe_devices(const std::vector<FoundDevice>& found) {
  std::string text;
  for (const auto& device : found) {
    char line[256];
    std::snprintf(line, sizeof line, "  %-24s  %-14s  %s%s%s\n",
                  device.serial.empty() ? "(serial unknown)" : device.serial.c_str(),
                  mode_name(device.mode), device.product.c_str(),
                  device.problem.empty() ? "" : "  ! ", device.problem.c_str());
    text += line;
  }
  return text;
}

Expected<FoundDevice> pick_controller(const std::vector<FoundDevice>& found,
                                      const std::optional<std::string>& serial, DeviceMode mode) {
  std::vector<FoundDevice> candidates;
  for (const auto& device : found)
    if (device.mode == mode && (!serial || device.serial == *serial)) candidates.push_back(device);
  if (candidates.size() == 1) return Expected<FoundDevice>::success(candidates.front());
  if (candidates.empty()) {
    std::string message =
        serial ? "no controller with serial number " + *serial + " in " + mode_name(mode) + " mode"
               : std::string("no controller in ") + mode_name(mode) + " mode is connected";
    if (!found.empty()) message += "; connected:\n" + describe_devices(found);
    return fail<FoundDevice>(ErrorKind::kNotFound, message);
  }
  return fail<FoundDevice>(ErrorKind::kAmbiguous,
                           std::to_string(candidates.size()) + " controllers in " +
                               mode_name(mode) +
                               " mode are connected and none was named: choose one with "
                               "--device SERIAL\n" +
                               describe_devices(candidates));
}

TransportOpener hid_opener(std::string serial) {
  return [serial]() -> Expected<std::unique_ptr<Transport>> {
    const auto found = find_application_devices();
    for (const auto& device : found)
      if (device.serial == serial) return HidapiTransport::open(device.hid_path, device.serial);
    return fail<std::unique_ptr<Transport>>(
        ErrorKind::kNotFound, "no controller with serial number " + serial + " is connected");
  };
}

}  // namespace flutterscan::device
