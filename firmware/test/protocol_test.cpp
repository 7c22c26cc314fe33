#include "flutterscan/common/protocol.hpp"

#include <gtest/gtest.h>

#include <array>
#include <vector>

namespace flutterscan::protocol {
namespace {

TEST(Protocol, CommandNumbersNeverChange) {
  // Renumbering breaks every deployed host or controller: these are fixed forever.
  EXPECT_EQ(static_cast<int>(Command::kGetInfo), 0x01);
  EXPECT_EQ(static_cast<int>(Command::kSetCode), 0x02);
  EXPECT_EQ(static_cast<int>(Command::kSelectCode), 0x03);
  EXPECT_EQ(static_cast<int>(Command::kSetTiming), 0x04);
  EXPECT_EQ(static_cast<int>(Command::kSetMode), 0x05);
  EXPECT_EQ(static_cast<int>(Command::kSetBrightness), 0x06);
  EXPECT_EQ(static_cast<int>(Command::kArm), 0x07);
  EXPECT_EQ(static_cast<int>(Command::kDisarm), 0x08);
  EXPECT_EQ(static_cast<int>(Command::kGetStatus), 0x09);
  EXPECT_EQ(static_cast<int>(Command::kSelfTest), 0x0A);
  EXPECT_EQ(static_cast<int>(Command::kSaveConfig), 0x0B);
  EXPECT_EQ(static_cast<int>(Command::kEnterBootloader), 0x0C);
  EXPECT_EQ(static_cast<int>(Command::kSetGuard), 0x0D);
  EXPECT_EQ(static_cast<int>(Command::kExposureEvent), 0x80);
  EXPECT_FALSE(is_request_command(0x00));
  EXPECT_TRUE(is_request_command(0x01));
  EXPECT_TRUE(is_request_command(0x0D));
  EXPECT_FALSE(is_request_command(0x0E));
  EXPECT_FALSE(is_request_command(0x80));
}

TEST(Protocol, UsbIdsArePidCodes) {
  EXPECT_EQ(kUsbVendorId, 0x1209);
  EXPECT_NE(kUsbProductIdApplication, kUsbProductIdBootloader);
}

TEST(Protocol, EveryStatusHasText) {
  for (int s = 0; s <= static_cast<int>(Status::kAboveCeiling); ++s)
    EXPECT_STRNE(status_text(static_cast<Status>(s)), "unknown status") << s;
  EXPECT_STREQ(status_text(static_cast<Status>(200)), "unknown status");
}

TEST(Protocol, RequestBytesAreLittleEndianAfterTheHeader) {
  std::array<std::uint8_t, kReportSize> report;
  report.fill(0xAA);
  const SetTimingRequest timing{0x12345678u, 0x0A0B0C0Du, 1, {}};
  ASSERT_EQ(encode_request(Command::kSetTiming, 7, timing, report), kReportSize);
  const std::vector<std::uint8_t> expected = {0x04, 7,    12,   0,    0x78, 0x56, 0x34, 0x12,
                                              0x0D, 0x0C, 0x0B, 0x0A, 1,    0,    0,    0};
  EXPECT_EQ(std::vector<std::uint8_t>(report.begin(), report.begin() + 16), expected);
  for (std::size_t i = 16; i < kReportSize; ++i) EXPECT_EQ(report[i], 0) << "padding at " << i;
}

TEST(Protocol, RoundTripsAnExposureEvent) {
  ExposureEvent event{};
  event.frame_counter = 42;
  event.slot_time_us = 100;
  event.start_time_us = 0x0102030405060708ull;
  event.encoder_delta = -17;
  event.pulse_width_us = 5200;
  event.flags = kEventCodeSwitched | kEventOverrun;
  event.code_id = 3;
  event.slot_count = 52;
  std::array<std::uint8_t, kReportSize> report{};
  ASSERT_EQ(encode_message(static_cast<std::uint8_t>(Command::kExposureEvent), 9, Status::kOk,
                           event, report),
            kReportSize);
  EXPECT_EQ(report[8 + 4], 0x08);  // start_time_us, lowest byte first
  const auto message = parse_message(report);
  ASSERT_TRUE(message.ok());
  EXPECT_EQ(message.value().header.command, 0x80);
  EXPECT_EQ(message.value().header.sequence, 9);
  const auto decoded = decode_payload<ExposureEvent>(message.value().payload);
  ASSERT_TRUE(decoded.ok());
  EXPECT_EQ(decoded.value().start_time_us, event.start_time_us);
  EXPECT_EQ(decoded.value().encoder_delta, -17);
  EXPECT_EQ(decoded.value().flags, event.flags);
  EXPECT_EQ(decoded.value().slot_count, 52);
}

TEST(Protocol, ParseRefusesReportsShorterThanTheirClaims) {
  std::array<std::uint8_t, kReportSize> report{};
  EXPECT_EQ(parse_message(std::span(report).first(3)).error(), Status::kBadLength);
  report[2] = 8;  // claims 8 payload bytes
  EXPECT_EQ(parse_message(std::span(report).first(11)).error(), Status::kBadLength);
  EXPECT_TRUE(parse_message(std::span(report).first(12)).ok());
  report[2] = 61;  // more than a report can hold
  EXPECT_EQ(parse_message(report).error(), Status::kBadLength);
  std::array<std::uint8_t, kReportSize + 1> too_long{};
  EXPECT_EQ(parse_message(too_long).error(), Status::kBadLength);
}

TEST(Protocol, RequestWithStatusByteSetIsRefused) {
  std::array<std::uint8_t, kReportSize> report{};
  report[0] = 0x01;
  report[3] = 1;
  EXPECT_EQ(parse_request(report).error(), Status::kBadHeader);
  EXPECT_TRUE(parse_message(report).ok());  // replies may carry a status
}

TEST(Protocol, ControllerStatesHaveTheirNamesAndOthersAreUnknown) {
  EXPECT_STREQ(controller_state_name(0), "idle");
  EXPECT_STREQ(controller_state_name(1), "armed");
  EXPECT_STREQ(controller_state_name(2), "exposing");
  EXPECT_STREQ(controller_state_name(3), "fault");
  EXPECT_STREQ(controller_state_name(4), "unknown");
}

TEST(Protocol, SyncModesHaveTheirNamesAndOthersAreUnknown) {
  EXPECT_STREQ(sync_mode_name(0), "slave");
  EXPECT_STREQ(sync_mode_name(1), "master");
  EXPECT_STREQ(sync_mode_name(2), "free-run");
  EXPECT_STREQ(sync_mode_name(3), "unknown");
}

TEST(Protocol, PayloadMustHaveTheExactSize) {
  std::array<std::uint8_t, 13> bytes{};
  EXPECT_EQ(decode_payload<SetTimingRequest>(std::span(bytes).first(11)).error(),
            Status::kBadLength);
  EXPECT_EQ(decode_payload<SetTimingRequest>(bytes).error(), Status::kBadLength);
  EXPECT_TRUE(decode_payload<SetTimingRequest>(std::span(bytes).first(12)).ok());
  EXPECT_EQ(expect_empty_payload(std::span(bytes).first(1)), Status::kBadLength);
  EXPECT_EQ(expect_empty_payload({}), Status::kOk);
}

TEST(Protocol, PeekHeaderReadsOnlyWhatIsThere) {
  const std::array<std::uint8_t, 2> partial = {0x05, 0x33};
  const MessageHeader header = peek_header(partial);
  EXPECT_EQ(header.command, 0x05);
  EXPECT_EQ(header.sequence, 0x33);
  EXPECT_EQ(header.payload_length, 0);
}

TEST(Protocol, EncodeRefusesASmallBuffer) {
  std::array<std::uint8_t, kReportSize - 1> small;
  small.fill(0x55);
  EXPECT_EQ(encode_request(Command::kArm, 1, small), 0u);
  for (const std::uint8_t b : small) EXPECT_EQ(b, 0x55);
}

}  // namespace
}  // namespace flutterscan::protocol
