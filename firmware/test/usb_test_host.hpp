#pragma once
// Host-side helpers for the USB tests: a SimBoard with an application image in
// flash, HID request/reply over the interrupt endpoints, and a DFU 1.1 host
// doing what dfu-util does (GETSTATUS polling after each block, manifest).

#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "flutterscan/common/protocol.hpp"
#include "flutterscan/firmware/sim/sim_board.hpp"
#include "flutterscan/firmware/usb/dfu.hpp"
#include "flutterscan/firmware/usb/usb_descriptors.hpp"

namespace flutterscan::firmware::test {

namespace proto = flutterscan::protocol;
using sim::BoardMode;
using sim::ControlResult;
using sim::OutResult;
using sim::SimBoard;
using usb::DfuRequest;
using usb::DfuState;
using usb::DfuStatus;

/// The image the board runs at the start of a test: version 2.3.4.
inline std::vector<std::uint8_t> factory_image() {
  return sim::make_application_image(kBoardIdStm32f405, 2, 3, 4, 20'000, 7);
}

/// \brief A board running factory_image(), enumerated.
inline void enumerate_or_fail(SimBoard& board) {
  const sim::Enumeration e = board.enumerate();
  ASSERT_TRUE(e.ok) << e.error;
}

/// \brief Sends a request report on the HID OUT endpoint.
template <typename... Payload>
OutResult send_request(SimBoard& board, proto::Command command, std::uint8_t sequence,
                       const Payload&... payload) {
  std::array<std::uint8_t, proto::kReportSize> report{};
  EXPECT_EQ(proto::encode_request(command, sequence, payload..., report), proto::kReportSize);
  return board.interrupt_out(usb::kHidOutEndpoint.address, report);
}

/// \brief The next report on the HID IN endpoint, if any.
inline std::optional<std::vector<std::uint8_t>> read_report(SimBoard& board) {
  return board.interrupt_in(usb::kHidInEndpoint.address);
}

/// \brief DFU GETSTATUS as a struct.
struct DfuStatusReply {
  bool stalled = true;
  DfuStatus status = DfuStatus::kOk;
  std::uint32_t poll_timeout_ms = 0;
  DfuState state = DfuState::kAppIdle;
};

inline DfuStatusReply dfu_get_status(SimBoard& board, std::uint16_t interface = 0) {
  const ControlResult r =
      board.control_transfer(usb::kDfuRequestIn, static_cast<std::uint8_t>(DfuRequest::kGetStatus),
                             0, interface, usb::kDfuStatusSize);
  DfuStatusReply s;
  if (r.stalled || r.data.size() != usb::kDfuStatusSize) return s;
  const proto::DfuStatusReply reply = proto::parse_dfu_status(
      std::span<const std::uint8_t, usb::kDfuStatusSize>(r.data.data(), usb::kDfuStatusSize));
  s.stalled = false;
  s.status = reply.status;
  s.poll_timeout_ms = reply.poll_timeout_ms;
  s.state = reply.state;
  return s;
}

inline ControlResult dfu_request(SimBoard& board, DfuRequest request, std::uint16_t value = 0,
                                 std::span<const std::uint8_t> data = {}) {
  return board.control_transfer(usb::kDfuRequestOut, static_cast<std::uint8_t>(request), value, 0,
                                static_cast<std::uint16_t>(data.size()), data);
}

/// \brief What a download left behind.
struct DownloadLog {
  std::vector<DfuStatusReply> statuses;  ///< every GETSTATUS reply, in order
  DfuStatusReply final_status;           ///< the last one
  bool dnload_stalled = false;
};

/// \brief dfu-util's download: blocks of `transfer` bytes numbered from
/// `first_block`, GETSTATUS until dfuDNLOAD-IDLE after each, the zero-length
/// DNLOAD, then GETSTATUS until dfuIDLE or dfuERROR. Stops at the first error.
inline DownloadLog dfu_download(SimBoard& board, std::span<const std::uint8_t> image,
                                std::size_t transfer = usb::kDfuTransferSize,
                                std::uint16_t first_block = 0) {
  DownloadLog log;
  auto poll_until = [&](DfuState done) {
    for (int i = 0; i < 10; ++i) {
      const DfuStatusReply s = dfu_get_status(board);
      log.statuses.push_back(s);
      log.final_status = s;
      if (s.stalled || s.state == done || s.state == DfuState::kError) return;
    }
  };
  std::uint16_t block = first_block;
  for (std::size_t at = 0; at < image.size(); at += transfer, ++block) {
    const auto chunk = image.subspan(at, std::min(transfer, image.size() - at));
    if (dfu_request(board, DfuRequest::kDnload, block, chunk).stalled) {
      log.dnload_stalled = true;
      return log;
    }
    poll_until(DfuState::kDnloadIdle);
    if (log.final_status.state != DfuState::kDnloadIdle) return log;
  }
  if (dfu_request(board, DfuRequest::kDnload, block).stalled) {
    log.dnload_stalled = true;
    return log;
  }
  poll_until(DfuState::kDfuIdle);
  return log;
}

/// \brief Puts a board into the bootloader through DFU_DETACH on the runtime interface.
inline void detach_to_bootloader(SimBoard& board) {
  const ControlResult r =
      board.control_transfer(usb::kDfuRequestOut, static_cast<std::uint8_t>(DfuRequest::kDetach),
                             1000, usb::kDfuRuntimeInterface, 0);
  ASSERT_FALSE(r.stalled);
  ASSERT_EQ(board.mode(), BoardMode::kBootloader);
  enumerate_or_fail(board);
}

}  // namespace flutterscan::firmware::test
