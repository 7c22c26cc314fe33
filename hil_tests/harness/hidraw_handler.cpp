#include "hidraw_handler.hpp"

#include <linux/hidraw.h>
#include <linux/input.h>
#include <sys/ioctl.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <thread>

namespace flutterscan::hil {

namespace {

/// Bytes per interrupt packet of the HID endpoints.
constexpr std::size_t kPacketSize = 64;
/// How long a write waits for the OUT endpoint to take its packets (the kernel
/// waits up to 5 s; shorter here because every handler shares one thread).
constexpr auto kWriteTimeout = std::chrono::milliseconds(500);

/// Copies `text` (NUL-terminated, cut to the buffer) into the ioctl's buffer of `size` bytes.
long copy_string(UMockdevIoctlData* arg, std::size_t size, const std::string& text) {
  UMockdevIoctlData* d = umockdev_ioctl_data_resolve(arg, 0, size, nullptr);
  if (d == nullptr) return -1;
  const std::size_t n = std::min(text.size() + 1, size);
  std::memset(d->data, 0, size);
  std::memcpy(d->data, text.c_str(), n > 0 ? n - 1 : 0);
  g_object_unref(d);
  return static_cast<long>(n);
}

}  // namespace

HidrawHandler::HidrawHandler(DevicePort& port, int generation, HidrawIdentity identity)
    : port_(port),
      generation_(generation),
      identity_(std::move(identity)),
      base_(umockdev_ioctl_base_new()) {
  g_signal_connect(base_, "handle-ioctl", G_CALLBACK(&HidrawHandler::on_ioctl), this);
  g_signal_connect(base_, "handle-read", G_CALLBACK(&HidrawHandler::on_read), this);
  g_signal_connect(base_, "handle-write", G_CALLBACK(&HidrawHandler::on_write), this);
}

HidrawHandler::~HidrawHandler() {
  g_signal_handlers_disconnect_by_data(base_, this);
  g_object_unref(base_);
}

gboolean HidrawHandler::on_ioctl(UMockdevIoctlBase*, UMockdevIoctlClient* client, gpointer self) {
  static_cast<HidrawHandler*>(self)->handle_ioctl(client);
  return TRUE;
}
gboolean HidrawHandler::on_read(UMockdevIoctlBase*, UMockdevIoctlClient* client, gpointer self) {
  static_cast<HidrawHandler*>(self)->handle_read(client);
  return TRUE;
}
gboolean HidrawHandler::on_write(UMockdevIoctlBase*, UMockdevIoctlClient* client, gpointer self) {
  static_cast<HidrawHandler*>(self)->handle_write(client);
  return TRUE;
}

void HidrawHandler::handle_ioctl(UMockdevIoctlClient* client) {
  const unsigned long request = umockdev_ioctl_client_get_request(client);
  UMockdevIoctlData* arg = umockdev_ioctl_client_get_arg(client);
  if (!port_.present(generation_)) {
    umockdev_ioctl_client_complete(client, -1, ENODEV);
    return;
  }
  const auto& rd = identity_.report_descriptor;
  if (request == HIDIOCGRDESCSIZE) {
    UMockdevIoctlData* d = umockdev_ioctl_data_resolve(arg, 0, sizeof(int), nullptr);
    const int size = static_cast<int>(rd.size());
    std::memcpy(d->data, &size, sizeof size);
    g_object_unref(d);
    umockdev_ioctl_client_complete(client, 0, 0);
    return;
  }
  if (request == HIDIOCGRDESC) {
    UMockdevIoctlData* d =
        umockdev_ioctl_data_resolve(arg, 0, sizeof(hidraw_report_descriptor), nullptr);
    auto* desc = reinterpret_cast<hidraw_report_descriptor*>(d->data);
    if (desc->size > HID_MAX_DESCRIPTOR_SIZE) {
      g_object_unref(d);
      umockdev_ioctl_client_complete(client, -1, EINVAL);
      return;
    }
    const std::size_t n = std::min<std::size_t>(desc->size, rd.size());
    std::copy_n(rd.begin(), n, desc->value);
    g_object_unref(d);
    umockdev_ioctl_client_complete(client, 0, 0);
    return;
  }
  if (request == HIDIOCGRAWINFO) {
    UMockdevIoctlData* d = umockdev_ioctl_data_resolve(arg, 0, sizeof(hidraw_devinfo), nullptr);
    auto* info = reinterpret_cast<hidraw_devinfo*>(d->data);
    info->bustype = BUS_USB;
    info->vendor = static_cast<__s16>(identity_.vendor_id);
    info->product = static_cast<__s16>(identity_.product_id);
    g_object_unref(d);
    umockdev_ioctl_client_complete(client, 0, 0);
    return;
  }
  const unsigned long nr = _IOC_NR(request);
  const std::size_t size = _IOC_SIZE(request);
  if (_IOC_TYPE(request) == 'H' && (nr == 0x04 || nr == 0x05 || nr == 0x08)) {
    const std::string& text = nr == 0x04   ? identity_.name
                              : nr == 0x05 ? identity_.phys
                                           : identity_.uniq;
    const long n = copy_string(arg, size, text);
    umockdev_ioctl_client_complete(client, n, n < 0 ? EFAULT : 0);
    return;
  }
  // Feature and input/output reports by ioctl: the interface has none.
  umockdev_ioctl_client_complete(client, -1, _IOC_TYPE(request) == 'H' ? EPIPE : ENOTTY);
}

void HidrawHandler::handle_read(UMockdevIoctlClient* client) {
  UMockdevIoctlData* arg = umockdev_ioctl_client_get_arg(client);
  const auto packet = port_.interrupt_in(generation_, identity_.in_endpoint);
  if (!packet) {
    umockdev_ioctl_client_complete(client, -1, ENODEV);
    return;
  }
  if (!*packet) {
    umockdev_ioctl_client_complete(client, -1, EAGAIN);
    return;
  }
  const std::size_t room = static_cast<std::size_t>(arg->data_len);
  const std::size_t n = std::min((*packet)->size(), room);
  std::copy_n((*packet)->begin(), n, arg->data);
  umockdev_ioctl_data_update(arg, 0, arg->data, static_cast<gint>(room));
  umockdev_ioctl_client_complete(client, static_cast<long>(n), 0);
}

void HidrawHandler::handle_write(UMockdevIoctlClient* client) {
  UMockdevIoctlData* arg = umockdev_ioctl_client_get_arg(client);
  const std::size_t count = static_cast<std::size_t>(arg->data_len);
  if (count == 0) {
    umockdev_ioctl_client_complete(client, -1, EINVAL);
    return;
  }
  // No numbered reports: byte 0 is report id 0 and is not sent (usbhid's output path).
  if (arg->data[0] != 0) {
    umockdev_ioctl_client_complete(client, -1, EINVAL);
    return;
  }
  const std::span<const std::uint8_t> report(arg->data + 1, count - 1);
  // One interrupt transfer: full packets, then the short rest (a zero-length
  // packet if the report is empty).
  std::size_t sent = 0;
  bool first = true;
  const auto deadline = std::chrono::steady_clock::now() + kWriteTimeout;
  while (first || sent < report.size()) {
    const std::size_t n = std::min(kPacketSize, report.size() - sent);
    const OutResult r =
        port_.interrupt_out(generation_, identity_.out_endpoint, report.subspan(sent, n));
    if (r == OutResult::kGone) {
      umockdev_ioctl_client_complete(client, -1, ENODEV);
      return;
    }
    if (r == OutResult::kNak) {
      if (std::chrono::steady_clock::now() > deadline) {
        umockdev_ioctl_client_complete(client, -1, ETIMEDOUT);
        return;
      }
      std::this_thread::sleep_for(std::chrono::microseconds(200));
      continue;
    }
    sent += n;
    first = false;
  }
  umockdev_ioctl_client_complete(client, static_cast<long>(count), 0);
}

}  // namespace flutterscan::hil
