#pragma once
// Turns HID request reports into Controller calls and their replies into HID
// reports. Every reply echoes the request's command and sequence and carries a
// status; a malformed or unknown request gets an error status and changes
// nothing. Freestanding C++20: no heap, no exceptions, no RTTI.

#include <cstddef>
#include <cstdint>
#include <span>

#include "flutterscan/common/protocol.hpp"
#include "flutterscan/firmware/controller.hpp"

namespace flutterscan::firmware {

/// \brief The command side of the HID interface.
class CommandHandler {
 public:
  /// \brief A handler for `controller` (which must outlive it).
  explicit CommandHandler(Controller& controller) : controller_(controller) {}

  /// \brief Handles one request report (up to kReportSize bytes) and writes the
  /// reply report into `reply` (kReportSize bytes). Returns the reply's size,
  /// 0 if `reply` is too small.
  std::size_t handle(std::span<const std::uint8_t> request, std::span<std::uint8_t> reply);

  /// \brief Writes the next exposure event as a report into `report`; returns
  /// its size, or 0 if no event is waiting or `report` is too small.
  std::size_t next_event_report(std::span<std::uint8_t> report);

  /// \brief GetInfo and GetStatus requests answered with kOk since this
  /// handler was made (saturating): the queries a host session starts with,
  /// which the application takes as "a host says it works"
  /// (boot_decision.hpp, BootConfirmation).
  std::uint32_t queries_answered() const { return queries_answered_; }

 private:
  void count_query() {
    if (queries_answered_ != UINT32_MAX) ++queries_answered_;
  }

  Controller& controller_;
  std::uint8_t event_sequence_ = 0;
  std::uint32_t queries_answered_ = 0;
};

}  // namespace flutterscan::firmware
