#pragma once
// A USB host on the emulated chip's OTG_FS core (emu_otg_fs.hpp), written from
// USB 2.0 chapters 8 and 9: a bus reset and enumeration at full speed, control
// transfers (SETUP, data stage, status stage) and the HID interface's
// interrupt endpoints (EP1 OUT: request reports, EP1 IN: replies and exposure
// events, polled once per 1 ms frame as a host does). Between its
// transactions the chip runs (Chip::run_for: the product image's main loop and
// its interrupts); a NAKed transaction is retried every kRetry of emulated
// time. Every answer is the product image's own, through its OTG_FS driver,
// device core and command handler.

#include <array>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "emu_chip.hpp"

namespace flutterscan::firmware::emu {

class UsbHost {
 public:
  using Report = std::array<std::uint8_t, 64>;
  using Setup = std::array<std::uint8_t, 8>;
  static constexpr std::uint64_t kFrame = Chip::kCyclesPerUs * 1000;
  static constexpr std::uint64_t kRetry = Chip::kCyclesPerUs * 20;
  /// How long a transaction or a reply may keep the host waiting.
  static constexpr std::uint64_t kTimeout = Chip::kCyclesPerUs * 50'000;

  explicit UsbHost(Chip& chip) : chip_(chip) {}

  /// Lets `cycles` pass on the bus, reading EP1 IN once per frame once
  /// configured (until the device leaves the bus).
  std::string run_for(std::uint64_t cycles);
  /// Waits for the pull-up, then: bus reset, GET_DESCRIPTOR(device) at address
  /// 0, SET_ADDRESS `address`, GET_DESCRIPTOR(configuration), SET_CONFIGURATION
  /// 1. "" or what went wrong.
  std::string enumerate(std::uint8_t address);
  /// A control read of up to `length` bytes: `data` holds what the device sent.
  std::string control_in(const Setup& setup, std::vector<std::uint8_t>* data);
  /// A control write of `data` (the SETUP's wLength).
  std::string control_out(const Setup& setup, std::span<const std::uint8_t> data);
  /// A control transfer without a data stage.
  std::string control_no_data(const Setup& setup);
  /// One HID request report on EP1 OUT, then EP1 IN until its reply (the
  /// report echoing its command and sequence). "" or what went wrong.
  std::string request(const Report& report, Report* reply);
  /// The device descriptor of the last enumeration.
  const std::vector<std::uint8_t>& device_descriptor() const { return device_descriptor_; }
  /// Configured and still on the bus.
  bool configured() const { return configured_; }
  /// Every exposure event (IN reports 0x80..0xFF) read so far.
  const std::vector<Report>& events() const { return events_; }

 private:
  std::string transact(const char* what, const std::function<OtgFs::Handshake()>& transaction,
                       bool status_of_set_address = false);
  std::string poll_in();
  std::string advance(std::uint64_t cycles);

  Chip& chip_;
  std::uint8_t address_ = 0;
  bool configured_ = false;
  std::uint64_t next_frame_ = 0;
  std::vector<std::uint8_t> device_descriptor_;
  std::vector<Report> events_;
  std::vector<Report> replies_;
};

}  // namespace flutterscan::firmware::emu
