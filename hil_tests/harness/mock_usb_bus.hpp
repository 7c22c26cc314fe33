#pragma once
// The umockdev testbed holding the board as Linux would show it: the USB device
// (sysfs attributes from the board's own descriptors and strings, and the
// usbdevfs node /dev/bus/usb/001/DDD served by a UsbdevfsHandler), its
// interfaces, and in application mode the HID device and its hidraw node
// (served by a HidrawHandler). sync() follows the board: a new enumeration
// (detach, manifest + reset, power cycle) removes the old device and adds the
// new one under a new device number, an unplug removes it.

#include <umockdev.h>

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "board_host.hpp"
#include "hidraw_handler.hpp"
#include "usbdevfs_handler.hpp"

namespace flutterscan::hil {

/// \brief The testbed and what it holds.
class MockUsbBus {
 public:
  /// \brief An empty testbed (sets UMOCKDEV_DIR for this process and its children).
  explicit MockUsbBus(BoardHost& host);
  ~MockUsbBus();
  MockUsbBus(const MockUsbBus&) = delete;
  MockUsbBus& operator=(const MockUsbBus&) = delete;

  /// \brief Whether umockdev made a testbed.
  bool ok() const { return testbed_ != nullptr; }
  /// \brief Makes the testbed match the board (add, replace or remove the device).
  /// Returns false if an enumeration failed (the message is on stderr).
  bool sync();

 private:
  struct Present {
    int generation = -1;
    std::vector<std::string> syspaths;  ///< children first
  };

  bool add(int number);
  void remove();

  BoardHost& host_;
  UMockdevTestbed* testbed_;
  std::optional<Present> present_;
  int next_devnum_ = 2;
  int next_hidraw_ = 0;
  // Handlers stay alive to the end: a client may still hold an fd of a removed node.
  std::vector<std::unique_ptr<UsbdevfsHandler>> usb_handlers_;
  std::vector<std::unique_ptr<HidrawHandler>> hidraw_handlers_;
};

}  // namespace flutterscan::hil
