#pragma once
// usbdevfs (/dev/bus/usb/BBB/DDD) emulated on a DevicePort: the ioctls libusb
// issues (GET_CAPABILITIES, CLAIMINTERFACE, RELEASEINTERFACE, GETDRIVER,
// DISCONNECT_CLAIM, SETINTERFACE, SETCONFIGURATION, CLEAR_HALT, RESETEP, RESET,
// SUBMITURB for control/interrupt/bulk, REAPURB(NDELAY), DISCARDURB, GET_SPEED).
// Control URBs complete at once; interrupt/bulk URBs wait in submission order
// per endpoint until the board takes (OUT) or has (IN) a packet, checked at
// every reap. Runs on umockdev's worker thread.

#include <umockdev.h>

#include <cstdint>
#include <deque>
#include <mutex>
#include <string>

#include "device_port.hpp"

namespace flutterscan::hil {

/// \brief The ioctl handler of one usbdevfs node.
class UsbdevfsHandler {
 public:
  /// \brief Serves enumeration `generation` of `port` at `devnode` (e.g. /dev/bus/usb/001/002).
  UsbdevfsHandler(DevicePort& port, int generation, std::string devnode);
  ~UsbdevfsHandler();
  UsbdevfsHandler(const UsbdevfsHandler&) = delete;
  UsbdevfsHandler& operator=(const UsbdevfsHandler&) = delete;

  /// \brief The umockdev handler object to attach to the testbed.
  UMockdevIoctlBase* ioctl_base() const { return base_; }
  const std::string& devnode() const { return devnode_; }
  int generation() const { return generation_; }

 private:
  struct Urb {
    UMockdevIoctlData* urb = nullptr;     ///< the client's struct usbdevfs_urb (a reference)
    UMockdevIoctlData* buffer = nullptr;  ///< its data buffer (owned by `urb`)
    unsigned long client_address = 0;
    std::size_t sent = 0;  ///< OUT: bytes the device has taken so far
  };

  static gboolean on_ioctl(UMockdevIoctlBase* base, UMockdevIoctlClient* client, gpointer self);
  void handle(UMockdevIoctlClient* client);
  void submit(UMockdevIoctlClient* client, UMockdevIoctlData* arg);
  void reap(UMockdevIoctlClient* client, UMockdevIoctlData* arg);
  void discard(UMockdevIoctlClient* client, UMockdevIoctlData* arg);
  /// Runs a control URB at once (setup in its first 8 bytes).
  void run_control(Urb& urb);
  /// Tries to complete waiting interrupt/bulk URBs.
  void progress_pending();

  DevicePort& port_;
  int generation_;
  std::string devnode_;
  UMockdevIoctlBase* base_;
  std::mutex mutex_;
  std::deque<Urb> pending_;    ///< interrupt/bulk URBs waiting for the device
  std::deque<Urb> completed_;  ///< ready to be reaped, in completion order
};

}  // namespace flutterscan::hil
