#include "usbdevfs_handler.hpp"

#include <linux/usb/ch9.h>
#include <linux/usbdevice_fs.h>
#include <sys/ioctl.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

namespace flutterscan::hil {

namespace {

/// What this emulated usbfs can do (USBDEVFS_GET_CAPABILITIES): transfers of any
/// length in one URB, zero-length packets, bulk continuation.
constexpr std::uint32_t kCapabilities = USBDEVFS_CAP_ZERO_PACKET | USBDEVFS_CAP_BULK_CONTINUATION |
                                        USBDEVFS_CAP_NO_PACKET_SIZE_LIM |
                                        USBDEVFS_CAP_REAP_AFTER_DISCONNECT;

/// Max packet size of the interrupt/bulk endpoints (full speed; the HID endpoints).
constexpr std::size_t kMaxPacket = 64;

usbdevfs_urb* urb_of(UMockdevIoctlData* data) {
  return reinterpret_cast<usbdevfs_urb*>(data->data);
}

}  // namespace

UsbdevfsHandler::UsbdevfsHandler(DevicePort& port, int generation, std::string devnode)
    : port_(port),
      generation_(generation),
      devnode_(std::move(devnode)),
      base_(umockdev_ioctl_base_new()) {
  g_signal_connect(base_, "handle-ioctl", G_CALLBACK(&UsbdevfsHandler::on_ioctl), this);
}

UsbdevfsHandler::~UsbdevfsHandler() {
  g_signal_handlers_disconnect_by_data(base_, this);
  std::lock_guard lock(mutex_);
  for (auto* list : {&pending_, &completed_})
    for (Urb& u : *list) {
      g_object_unref(u.buffer);
      g_object_unref(u.urb);
    }
  g_object_unref(base_);
}

gboolean UsbdevfsHandler::on_ioctl(UMockdevIoctlBase* /*base*/, UMockdevIoctlClient* client,
                                   gpointer self) {
  static_cast<UsbdevfsHandler*>(self)->handle(client);
  return TRUE;
}

void UsbdevfsHandler::handle(UMockdevIoctlClient* client) {
  const unsigned long request = umockdev_ioctl_client_get_request(client);
  UMockdevIoctlData* arg = umockdev_ioctl_client_get_arg(client);
  std::lock_guard lock(mutex_);

  // After a disconnect only reaping (of what was cancelled) still works.
  const bool present = port_.present(generation_);
  if (!present && request != USBDEVFS_REAPURBNDELAY && request != USBDEVFS_REAPURB &&
      request != USBDEVFS_DISCARDURB) {
    umockdev_ioctl_client_complete(client, -1, ENODEV);
    return;
  }

  switch (request) {
    case USBDEVFS_GET_CAPABILITIES: {
      UMockdevIoctlData* d = umockdev_ioctl_data_resolve(arg, 0, sizeof(std::uint32_t), nullptr);
      std::memcpy(d->data, &kCapabilities, sizeof kCapabilities);
      g_object_unref(d);
      umockdev_ioctl_client_complete(client, 0, 0);
      return;
    }
    case USBDEVFS_CLAIMINTERFACE:
    case USBDEVFS_RELEASEINTERFACE:
    case USBDEVFS_DISCONNECT_CLAIM:
    case USBDEVFS_RESETEP:
      umockdev_ioctl_client_complete(client, 0, 0);
      return;
    case USBDEVFS_GETDRIVER:
      // No kernel driver is bound to any interface (usbhid's place is taken by
      // the hidraw emulation, which does not need the interface).
      umockdev_ioctl_client_complete(client, -1, ENODATA);
      return;
    case USBDEVFS_IOCTL:
      // Connecting/disconnecting kernel drivers: there are none.
      umockdev_ioctl_client_complete(client, -1, ENODATA);
      return;
    case USBDEVFS_GET_SPEED:
      umockdev_ioctl_client_complete(client, 2 /* USB_SPEED_FULL */, 0);
      return;
    case USBDEVFS_SETINTERFACE:
    case USBDEVFS_SETCONFIGURATION:
    case USBDEVFS_CLEAR_HALT: {
      const std::size_t size =
          request == USBDEVFS_SETINTERFACE ? sizeof(usbdevfs_setinterface) : sizeof(unsigned int);
      UMockdevIoctlData* d = umockdev_ioctl_data_resolve(arg, 0, size, nullptr);
      std::array<std::uint8_t, 8> setup{};
      if (request == USBDEVFS_SETINTERFACE) {
        const auto* s = reinterpret_cast<const usbdevfs_setinterface*>(d->data);
        setup = make_setup(0x01, USB_REQ_SET_INTERFACE, static_cast<std::uint16_t>(s->altsetting),
                           static_cast<std::uint16_t>(s->interface), 0);
      } else {
        unsigned int value = 0;
        std::memcpy(&value, d->data, sizeof value);
        setup = request == USBDEVFS_SETCONFIGURATION
                    ? make_setup(0x00, USB_REQ_SET_CONFIGURATION, static_cast<std::uint16_t>(value),
                                 0, 0)
                    : make_setup(0x02, USB_REQ_CLEAR_FEATURE, USB_ENDPOINT_HALT,
                                 static_cast<std::uint16_t>(value & 0xFF), 0);
      }
      g_object_unref(d);
      const auto outcome = port_.control(generation_, setup, {});
      if (!outcome)
        umockdev_ioctl_client_complete(client, -1, ENODEV);
      else if (outcome->stalled)
        umockdev_ioctl_client_complete(client, -1, EPIPE);
      else
        umockdev_ioctl_client_complete(client, 0, 0);
      return;
    }
    case USBDEVFS_RESET:
      umockdev_ioctl_client_complete(client, port_.reset(generation_) ? 0 : -1,
                                     port_.present(generation_) ? 0 : ENODEV);
      return;
    case USBDEVFS_SUBMITURB:
      submit(client, arg);
      return;
    case USBDEVFS_REAPURB:
    case USBDEVFS_REAPURBNDELAY:
      reap(client, arg);
      return;
    case USBDEVFS_DISCARDURB:
      discard(client, arg);
      return;
    default:
      umockdev_ioctl_client_complete(client, -1, ENOTTY);
      return;
  }
}

void UsbdevfsHandler::submit(UMockdevIoctlClient* client, UMockdevIoctlData* arg) {
  UMockdevIoctlData* urb_data = umockdev_ioctl_data_resolve(arg, 0, sizeof(usbdevfs_urb), nullptr);
  usbdevfs_urb* urb = urb_of(urb_data);
  if (urb->type == USBDEVFS_URB_TYPE_ISO || urb->buffer_length < 0 ||
      (urb->type == USBDEVFS_URB_TYPE_CONTROL && urb->buffer_length < 8)) {
    g_object_unref(urb_data);
    umockdev_ioctl_client_complete(client, -1, EINVAL);
    return;
  }
  Urb u;
  u.urb = urb_data;
  u.client_address = urb_data->client_addr;
  u.buffer = umockdev_ioctl_data_resolve(urb_data, offsetof(usbdevfs_urb, buffer),
                                         static_cast<std::size_t>(urb->buffer_length), nullptr);
  if (u.buffer == nullptr && urb->buffer_length > 0) {
    g_object_unref(urb_data);
    umockdev_ioctl_client_complete(client, -1, EFAULT);
    return;
  }
  if (u.buffer == nullptr) u.buffer = static_cast<UMockdevIoctlData*>(g_object_ref(urb_data));
  urb->status = 0;
  urb->actual_length = 0;
  if (urb->type == USBDEVFS_URB_TYPE_CONTROL) {
    run_control(u);
    completed_.push_back(u);
  } else {
    pending_.push_back(u);
    progress_pending();
  }
  umockdev_ioctl_client_complete(client, 0, 0);
}

void UsbdevfsHandler::run_control(Urb& u) {
  usbdevfs_urb* urb = urb_of(u.urb);
  std::uint8_t* bytes = urb->buffer_length > 0 ? u.buffer->data : nullptr;
  std::array<std::uint8_t, 8> setup{};
  std::copy_n(bytes, 8, setup.begin());
  const std::size_t data_room = static_cast<std::size_t>(urb->buffer_length) - 8;
  const std::uint16_t length = static_cast<std::uint16_t>(setup[6] | setup[7] << 8);
  const bool in = (setup[0] & 0x80) != 0;
  const std::size_t out_length = in ? 0 : std::min<std::size_t>(length, data_room);
  const auto outcome =
      port_.control(generation_, setup, std::span<const std::uint8_t>(bytes + 8, out_length));
  if (!outcome) {
    urb->status = -ENODEV;
    return;
  }
  if (outcome->stalled) {
    urb->status = -EPIPE;
    return;
  }
  if (in) {
    const std::size_t n = std::min({outcome->in_data.size(), data_room, std::size_t{length}});
    std::copy_n(outcome->in_data.begin(), n, bytes + 8);
    urb->actual_length = static_cast<int>(n);
  } else {
    urb->actual_length = static_cast<int>(out_length);
  }
}

void UsbdevfsHandler::progress_pending() {
  // Endpoints are independent, but per endpoint URBs complete in order: only
  // the oldest URB of each endpoint may move.
  std::array<bool, 32> blocked{};
  for (auto it = pending_.begin(); it != pending_.end();) {
    usbdevfs_urb* urb = urb_of(it->urb);
    const std::uint8_t ep = urb->endpoint;
    const std::size_t slot = (ep & 0x0F) + ((ep & 0x80) ? 16 : 0);
    if (blocked[slot]) {
      ++it;
      continue;
    }
    bool done = false;
    if (ep & 0x80) {
      const auto packet = port_.interrupt_in(generation_, ep);
      if (!packet) {
        urb->status = -ENODEV;
        done = true;
      } else if (*packet) {
        const std::size_t n =
            std::min((*packet)->size(), static_cast<std::size_t>(urb->buffer_length));
        std::copy_n((*packet)->begin(), n, it->buffer->data);
        // A packet longer than the buffer: -EOVERFLOW, as the host controller reports babble.
        urb->status = (*packet)->size() > n ? -EOVERFLOW : 0;
        urb->actual_length = static_cast<int>(n);
        done = true;
      }
    } else {
      // The host controller splits a transfer into max-packet pieces (a short
      // or zero-length one ends it).
      const std::size_t total = static_cast<std::size_t>(urb->buffer_length);
      for (;;) {
        const std::size_t n = std::min(kMaxPacket, total - it->sent);
        const OutResult r = port_.interrupt_out(
            generation_, ep,
            std::span<const std::uint8_t>(n > 0 ? it->buffer->data + it->sent : nullptr, n));
        if (r == OutResult::kGone) {
          urb->status = -ENODEV;
          done = true;
          break;
        }
        if (r == OutResult::kNak) break;
        it->sent += n;
        if (it->sent == total) {
          urb->actual_length = static_cast<int>(total);
          done = true;
          break;
        }
      }
    }
    if (done) {
      completed_.push_back(*it);
      it = pending_.erase(it);
    } else {
      blocked[slot] = true;
      ++it;
    }
  }
}

void UsbdevfsHandler::reap(UMockdevIoctlClient* client, UMockdevIoctlData* arg) {
  if (completed_.empty()) {
    if (!port_.present(generation_)) {
      // Disconnected: everything still in flight ends with -ENODEV (REAP_AFTER_DISCONNECT).
      for (Urb& u : pending_) urb_of(u.urb)->status = -ENODEV;
      completed_.insert(completed_.end(), pending_.begin(), pending_.end());
      pending_.clear();
    } else {
      progress_pending();
    }
  }
  if (completed_.empty()) {
    umockdev_ioctl_client_complete(client, -1, port_.present(generation_) ? EAGAIN : ENODEV);
    return;
  }
  Urb u = completed_.front();
  completed_.pop_front();
  UMockdevIoctlData* slot = umockdev_ioctl_data_resolve(arg, 0, sizeof(void*), nullptr);
  umockdev_ioctl_data_set_ptr(slot, 0, u.urb);
  g_object_unref(slot);
  g_object_unref(u.buffer);
  g_object_unref(u.urb);
  umockdev_ioctl_client_complete(client, 0, 0);
}

void UsbdevfsHandler::discard(UMockdevIoctlClient* client, UMockdevIoctlData* arg) {
  unsigned long address = 0;
  std::memcpy(&address, arg->data, sizeof address);
  const auto it = std::find_if(pending_.begin(), pending_.end(),
                               [&](const Urb& u) { return u.client_address == address; });
  if (it == pending_.end()) {
    umockdev_ioctl_client_complete(client, -1, EINVAL);
    return;
  }
  urb_of(it->urb)->status = -ENOENT;
  completed_.push_back(*it);
  pending_.erase(it);
  umockdev_ioctl_client_complete(client, 0, 0);
}

}  // namespace flutterscan::hil
