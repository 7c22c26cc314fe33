// The HID interface through SimUsbController: command round trips, exposure
// events on the IN endpoint while replies are pending (replies first, nothing
// dropped), flow control when the host stops reading, EnterBootloader and
// DFU_DETACH re-enumerating as the bootloader.

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "flutterscan/common/led_code.hpp"
#include "usb_test_host.hpp"

namespace flutterscan::firmware::test {
namespace {

class UsbHidTest : public ::testing::Test {
 protected:
  UsbHidTest() : image_(factory_image()), board_(sim::SimBoardConfig{}, image_) {
    const sim::Enumeration e = board_.enumerate();
    EXPECT_TRUE(e.ok) << e.error;
  }

  /// Sends a request and reads its reply (the test fails if there is none).
  template <typename... Payload>
  std::vector<std::uint8_t> round_trip(proto::Command command, const Payload&... payload) {
    EXPECT_EQ(send_request(board_, command, ++sequence_, payload...), OutResult::kAck);
    auto reply = read_report(board_);
    EXPECT_TRUE(reply.has_value());
    if (!reply) return {};
    EXPECT_EQ(reply->size(), proto::kReportSize);
    EXPECT_EQ(proto::peek_header(*reply).command, static_cast<std::uint8_t>(command));
    EXPECT_EQ(proto::peek_header(*reply).sequence, sequence_);
    return *reply;
  }

  /// Uploads a one-of-3 code (masks 1, 2, 4 twice), sets 2 ms free-run frames and arms.
  void arm_free_run() {
    const auto code = LedCode::parse("124124", 3);
    ASSERT_TRUE(code.ok());
    proto::SetCodeRequest r{};
    r.code_id = 0;
    r.led_count = 3;
    r.total_slots = 6;
    r.first_slot = 0;
    r.slot_count = 6;
    for (int i = 0; i < 6; ++i) r.masks[static_cast<std::size_t>(i)] = code.value().mask(i);
    expect_ok(round_trip(proto::Command::kSetCode, r));
    expect_ok(round_trip(proto::Command::kSelectCode, proto::SelectCodeRequest{0, {}}));
    proto::SetGuardRequest guard{};  // the board's ceiling, the most it allows
    guard.max_on_time_us.fill(kProductLedCeiling.max_on_time_us[0]);
    guard.max_duty_permille.fill(kProductLedCeiling.max_duty_permille[0]);
    expect_ok(round_trip(proto::Command::kSetGuard, guard));
    expect_ok(
        round_trip(proto::Command::kSetTiming,
                   proto::SetTimingRequest{
                       100, 2'000, static_cast<std::uint8_t>(proto::SlotTimeSource::kFixed), {}}));
    expect_ok(round_trip(
        proto::Command::kSetMode,
        proto::SetModeRequest{static_cast<std::uint8_t>(proto::SyncMode::kFreeRun), 0, {}}));
    expect_ok(round_trip(proto::Command::kArm));
  }

  static void expect_ok(const std::vector<std::uint8_t>& reply) {
    ASSERT_FALSE(reply.empty());
    EXPECT_EQ(proto::peek_header(reply).status, static_cast<std::uint8_t>(proto::Status::kOk))
        << "command " << int{proto::peek_header(reply).command};
  }

  std::vector<std::uint8_t> image_;
  SimBoard board_;
  std::uint8_t sequence_ = 0;
};

TEST_F(UsbHidTest, GetInfoReportsTheFlashedImage) {
  const auto reply = round_trip(proto::Command::kGetInfo);
  ASSERT_FALSE(reply.empty());
  const auto info =
      proto::decode_payload<proto::InfoReply>(std::span<const std::uint8_t>(reply).subspan(
          proto::kHeaderSize, proto::peek_header(reply).payload_length));
  ASSERT_TRUE(info.ok());
  EXPECT_EQ(info.value().protocol_major, proto::kProtocolMajor);
  EXPECT_EQ(info.value().firmware_major, 2);
  EXPECT_EQ(info.value().firmware_minor, 3);
  EXPECT_EQ(info.value().firmware_patch, 4);
  EXPECT_EQ(info.value().board_id, kBoardIdStm32f405);
  EXPECT_EQ(info.value().build_id, read_image_header(image_).image_crc32);
  EXPECT_FALSE(read_report(board_).has_value());  // one reply per request
}

TEST_F(UsbHidTest, MalformedReportsGetAnErrorReplyAndChangeNothing) {
  std::array<std::uint8_t, proto::kReportSize> garbage{};
  garbage.fill(0xEE);
  ASSERT_EQ(board_.interrupt_out(0x01, garbage), OutResult::kAck);
  auto reply = read_report(board_);
  ASSERT_TRUE(reply.has_value());
  EXPECT_NE(proto::peek_header(*reply).status, static_cast<std::uint8_t>(proto::Status::kOk));
  // A short and an empty packet, too.
  ASSERT_EQ(board_.interrupt_out(0x01, std::span<const std::uint8_t>(garbage).first(3)),
            OutResult::kAck);
  reply = read_report(board_);
  ASSERT_TRUE(reply.has_value());
  EXPECT_NE(proto::peek_header(*reply).status, static_cast<std::uint8_t>(proto::Status::kOk));
  ASSERT_EQ(board_.interrupt_out(0x01, {}), OutResult::kAck);
  ASSERT_TRUE(read_report(board_).has_value());
  // Too long for the endpoint: not even accepted.
  const std::vector<std::uint8_t> long_packet(65, 0);
  EXPECT_EQ(board_.interrupt_out(0x01, long_packet), OutResult::kNoEndpoint);
  EXPECT_EQ(board_.controller()->state(), proto::ControllerState::kIdle);
  expect_ok(round_trip(proto::Command::kGetStatus));
}

TEST_F(UsbHidTest, EventsFlowOnInAndRepliesGoFirst) {
  arm_free_run();
  // 2 ms frames: run 5 frames without reading; five events wait in the controller.
  board_.run_for(9'000);
  // Two requests while events are waiting: their replies overtake the events.
  ASSERT_EQ(send_request(board_, proto::Command::kGetStatus, 100), OutResult::kAck);
  ASSERT_EQ(send_request(board_, proto::Command::kGetStatus, 101), OutResult::kAck);
  std::vector<std::vector<std::uint8_t>> reports;
  while (auto r = read_report(board_)) reports.push_back(*r);
  ASSERT_GE(reports.size(), 3u);
  // The first report may be an event already on the endpoint before the
  // requests came; every reply comes before every event queued after it.
  std::size_t first_reply = 0;
  while (first_reply < reports.size() &&
         proto::peek_header(reports[first_reply]).command ==
             static_cast<std::uint8_t>(proto::Command::kExposureEvent))
    ++first_reply;
  ASSERT_LE(first_reply, 1u);
  ASSERT_LT(first_reply + 1, reports.size());
  EXPECT_EQ(proto::peek_header(reports[first_reply]).sequence, 100);
  EXPECT_EQ(proto::peek_header(reports[first_reply + 1]).sequence, 101);
  // Then the events: consecutive frame counters, none missing.
  std::vector<std::uint32_t> frames;
  for (std::size_t i = 0; i < reports.size(); ++i) {
    if (i == first_reply || i == first_reply + 1) continue;
    ASSERT_EQ(proto::peek_header(reports[i]).command,
              static_cast<std::uint8_t>(proto::Command::kExposureEvent));
    const auto event = proto::decode_payload<proto::ExposureEvent>(
        std::span<const std::uint8_t>(reports[i])
            .subspan(proto::kHeaderSize, proto::peek_header(reports[i]).payload_length));
    ASSERT_TRUE(event.ok());
    frames.push_back(event.value().frame_counter);
  }
  ASSERT_EQ(frames.size(), 5u);
  for (std::size_t i = 1; i < frames.size(); ++i) EXPECT_EQ(frames[i], frames[i - 1] + 1);
  // Events keep coming as time runs.
  board_.run_for(2'000);
  const auto next = read_report(board_);
  ASSERT_TRUE(next.has_value());
  EXPECT_EQ(proto::peek_header(*next).command,
            static_cast<std::uint8_t>(proto::Command::kExposureEvent));
}

TEST_F(UsbHidTest, AHostThatStopsReadingGetsNakNotLostReplies) {
  // The IN endpoint holds one reply, the queue four more, the handler one request.
  int acked = 0;
  for (int i = 0; i < 10; ++i) {
    const OutResult r =
        send_request(board_, proto::Command::kGetStatus, static_cast<std::uint8_t>(i));
    if (r == OutResult::kAck)
      ++acked;
    else
      EXPECT_EQ(r, OutResult::kNak);
  }
  EXPECT_EQ(acked, 6);
  EXPECT_TRUE(board_.application()->hid().request_pending());
  // Every accepted request is answered, in order.
  for (int i = 0; i < acked; ++i) {
    const auto reply = read_report(board_);
    ASSERT_TRUE(reply.has_value()) << i;
    EXPECT_EQ(proto::peek_header(*reply).sequence, i);
  }
  EXPECT_FALSE(read_report(board_).has_value());
  EXPECT_EQ(send_request(board_, proto::Command::kGetStatus, 50), OutResult::kAck);
  EXPECT_EQ(proto::peek_header(*read_report(board_)).sequence, 50);
}

TEST_F(UsbHidTest, SetIdleAndGetIdle) {
  EXPECT_FALSE(board_.control_transfer(0x21, usb::kHidSetIdle, 0x0400, 0, 0).stalled);
  const ControlResult idle = board_.control_transfer(0xA1, usb::kHidGetIdle, 0, 0, 1);
  ASSERT_FALSE(idle.stalled);
  EXPECT_EQ(idle.data, (std::vector<std::uint8_t>{4}));
}

TEST_F(UsbHidTest, DfuRuntimeReportsAppIdle) {
  const DfuStatusReply s = dfu_get_status(board_, usb::kDfuRuntimeInterface);
  ASSERT_FALSE(s.stalled);
  EXPECT_EQ(s.status, DfuStatus::kOk);
  EXPECT_EQ(s.state, DfuState::kAppIdle);
  const ControlResult state = board_.control_transfer(
      0xA1, static_cast<std::uint8_t>(DfuRequest::kGetState), 0, usb::kDfuRuntimeInterface, 1);
  EXPECT_EQ(state.data, (std::vector<std::uint8_t>{0}));
}

TEST_F(UsbHidTest, DfuDetachTurnsLedsOffAndReEnumeratesAsTheBootloader) {
  arm_free_run();
  std::vector<std::pair<BoardMode, std::uint32_t>> seen;
  board_.on_reenumerate([&](BoardMode m, std::uint32_t epoch) { seen.emplace_back(m, epoch); });
  const std::uint32_t epoch = board_.epoch();
  board_.run_for(2'150);  // inside an exposure, slot 1 (LED 0 on)
  ASSERT_NE(board_.port().led_mask(), 0);
  const ControlResult r =
      board_.control_transfer(usb::kDfuRequestOut, static_cast<std::uint8_t>(DfuRequest::kDetach),
                              1000, usb::kDfuRuntimeInterface, 0);
  EXPECT_FALSE(r.stalled);
  EXPECT_EQ(board_.port().led_mask(), 0);
  EXPECT_EQ(board_.mode(), BoardMode::kBootloader);
  EXPECT_EQ(board_.epoch(), epoch + 1);
  ASSERT_EQ(seen.size(), 1u);
  EXPECT_EQ(seen[0].first, BoardMode::kBootloader);
  EXPECT_EQ(seen[0].second, epoch + 1);
  EXPECT_EQ(board_.port().bootloader_entries(), 1);
  const sim::Enumeration e = board_.enumerate();
  ASSERT_TRUE(e.ok) << e.error;
  EXPECT_EQ(board_.product_id(), proto::kUsbProductIdBootloader);
  EXPECT_EQ(e.serial, board_.serial());
  EXPECT_EQ(dfu_get_status(board_).state, DfuState::kDfuIdle);
  // A plain reset (no hand-off word) starts the untouched application again.
  board_.reset();
  EXPECT_EQ(board_.mode(), BoardMode::kApplication);
}

TEST_F(UsbHidTest, EnterBootloaderCommandSendsItsReplyFirst) {
  ASSERT_EQ(send_request(board_, proto::Command::kEnterBootloader, 9,
                         proto::EnterBootloaderRequest{proto::kEnterBootloaderMagic}),
            OutResult::kAck);
  // Not yet: the reply has not been read.
  EXPECT_EQ(board_.mode(), BoardMode::kApplication);
  const auto reply = read_report(board_);
  ASSERT_TRUE(reply.has_value());
  EXPECT_EQ(proto::peek_header(*reply).sequence, 9);
  EXPECT_EQ(proto::peek_header(*reply).status, static_cast<std::uint8_t>(proto::Status::kOk));
  EXPECT_EQ(board_.mode(), BoardMode::kBootloader);
}

TEST_F(UsbHidTest, EnterBootloaderGoesAnywayIfTheReplyIsNeverRead) {
  ASSERT_EQ(send_request(board_, proto::Command::kEnterBootloader, 9,
                         proto::EnterBootloaderRequest{proto::kEnterBootloaderMagic}),
            OutResult::kAck);
  for (int i = 0;
       i < usb::kBootloaderReplyWaitPolls + 1 && board_.mode() == BoardMode::kApplication; ++i)
    board_.run_for(1'000);
  EXPECT_EQ(board_.mode(), BoardMode::kBootloader);
}

}  // namespace
}  // namespace flutterscan::firmware::test
