// The virtual controller: the firmware core answering HID reports, the
// physical side on the virtual clock, and the fault knobs tests rely on.
#include "device/virtual_controller.hpp"

#include <gtest/gtest.h>

#include <string_view>
#include <thread>

namespace flutterscan::device {
namespace {

namespace proto = flutterscan::protocol;

constexpr std::string_view kCode = "2212441414112412441224111241244244242212442211444144";

Report encode(proto::Command command, std::uint8_t sequence) {
  Report report{};
  EXPECT_EQ(proto::encode_request(command, sequence, report), proto::kReportSize);
  return report;
}

template <typename T>
Report encode(proto::Command command, std::uint8_t sequence, const T& payload) {
  Report report{};
  EXPECT_EQ(proto::encode_request(command, sequence, payload, report), proto::kReportSize);
  return report;
}

proto::Status status_of(const Report& reply) {
  return static_cast<proto::Status>(reply[3]);
}

template <typename T>
T payload_of(const Report& reply) {
  const auto message = proto::parse_message(reply);
  EXPECT_TRUE(message.ok());
  const auto value = proto::decode_payload<T>(message.value().payload);
  EXPECT_TRUE(value.ok());
  return value.value();
}

/// Uploads kCode as code 0, selects it, 100 us slots, arms (slave mode).
void arm_with_code(VirtualController& vc) {
  proto::SetCodeRequest chunk{};
  chunk.code_id = 0;
  chunk.led_count = 3;
  chunk.total_slots = static_cast<std::uint16_t>(kCode.size());
  chunk.slot_count = static_cast<std::uint8_t>(kCode.size());
  chunk.flags = proto::kCodeFlagOneOfN;
  for (std::size_t i = 0; i < kCode.size(); ++i)
    chunk.masks[i] = static_cast<std::uint8_t>(kCode[i] - '0');
  ASSERT_EQ(status_of(vc.request(encode(proto::Command::kSetCode, 1, chunk))), proto::Status::kOk);
  ASSERT_EQ(status_of(vc.request(
                encode(proto::Command::kSelectCode, 2, proto::SelectCodeRequest{0, {}}))),
            proto::Status::kOk);
  ASSERT_EQ(status_of(vc.request(
                encode(proto::Command::kSetTiming, 3, proto::SetTimingRequest{100, 0, 0, {}}))),
            proto::Status::kOk);
  ASSERT_EQ(status_of(vc.request(encode(proto::Command::kArm, 4))), proto::Status::kOk);
}

TEST(VirtualController, AnswersGetInfoWithTheBuildsVersion) {
  VirtualController vc;
  const Report reply = vc.request(encode(proto::Command::kGetInfo, 7));
  EXPECT_EQ(reply[0], static_cast<std::uint8_t>(proto::Command::kGetInfo));
  EXPECT_EQ(reply[1], 7);
  ASSERT_EQ(status_of(reply), proto::Status::kOk);
  const auto info = payload_of<proto::InfoReply>(reply);
  EXPECT_EQ(info.protocol_major, proto::kProtocolMajor);
  EXPECT_EQ(info.led_count, 3);
  EXPECT_EQ(info.firmware_major, FLUTTERSCAN_VERSION_MAJOR);
  EXPECT_EQ(info.firmware_minor, FLUTTERSCAN_VERSION_MINOR);
  EXPECT_EQ(vc.serial_number(), kVirtualSerial);
}

TEST(VirtualController, ReportsAnotherProtocolMajorWhenTold) {
  VirtualControllerOptions options;
  options.reported_protocol_major = proto::kProtocolMajor + 1;
  VirtualController vc(options);
  const auto info = payload_of<proto::InfoReply>(vc.request(encode(proto::Command::kGetInfo, 1)));
  EXPECT_EQ(info.protocol_major, proto::kProtocolMajor + 1);
}

TEST(VirtualController, ExposurePlaysTheCodeAndQueuesOneEvent) {
  VirtualController vc;
  arm_with_code(vc);
  vc.take_led_transitions();
  vc.add_encoder_counts(0);
  const std::uint64_t start = vc.now_us();
  vc.expose(6000);
  const auto transitions = vc.take_led_transitions();
  ASSERT_EQ(transitions.size(), kCode.size() + 1);
  for (std::size_t i = 0; i < kCode.size(); ++i) {
    EXPECT_EQ(transitions[i].time_us, start + i * 100) << "slot " << i;
    EXPECT_EQ(transitions[i].led_mask, kCode[i] - '0') << "slot " << i;
  }
  EXPECT_EQ(transitions.back().led_mask, 0);
  EXPECT_EQ(vc.led_mask(), 0);
  EXPECT_GE(vc.now_us(), start + 6000);

  const auto event_report = vc.next_event_report();
  ASSERT_TRUE(event_report.has_value());
  EXPECT_EQ((*event_report)[0], static_cast<std::uint8_t>(proto::Command::kExposureEvent));
  const auto event = payload_of<proto::ExposureEvent>(*event_report);
  EXPECT_EQ(event.frame_counter, 1u);
  EXPECT_EQ(event.slot_time_us, 100u);
  EXPECT_EQ(event.slot_count, kCode.size());
  EXPECT_FALSE(vc.next_event_report().has_value());
}

TEST(VirtualController, InQueueCarriesRepliesBeforeEvents) {
  VirtualController vc;
  arm_with_code(vc);
  vc.expose(6000);
  ASSERT_TRUE(vc.write_report(encode(proto::Command::kGetStatus, 9)));
  const auto first = vc.read_report();
  ASSERT_TRUE(first.has_value());
  EXPECT_EQ((*first)[0], static_cast<std::uint8_t>(proto::Command::kGetStatus));
  EXPECT_EQ((*first)[1], 9);
  const auto second = vc.read_report();
  ASSERT_TRUE(second.has_value());
  EXPECT_EQ((*second)[0], static_cast<std::uint8_t>(proto::Command::kExposureEvent));
  EXPECT_FALSE(vc.read_report().has_value());
}

TEST(VirtualController, UnresponsiveSwallowsRequests) {
  VirtualController vc;
  vc.set_responsive(false);
  EXPECT_TRUE(vc.write_report(encode(proto::Command::kGetInfo, 1)));
  EXPECT_FALSE(vc.read_report().has_value());
  EXPECT_EQ(vc.request(encode(proto::Command::kGetInfo, 2))[0], 0);
  vc.set_responsive(true);
  EXPECT_EQ(vc.request(encode(proto::Command::kGetInfo, 3))[0],
            static_cast<std::uint8_t>(proto::Command::kGetInfo));
}

TEST(VirtualController, UnplugFailsWritesAndReplugBootsWithSavedConfig) {
  VirtualController vc;
  arm_with_code(vc);
  ASSERT_EQ(status_of(vc.request(encode(proto::Command::kDisarm, 5))), proto::Status::kOk);
  ASSERT_EQ(status_of(vc.request(encode(proto::Command::kSaveConfig, 6))), proto::Status::kOk);
  vc.advance_us(1'000'000);
  vc.unplug();
  EXPECT_FALSE(vc.plugged_in());
  EXPECT_FALSE(vc.write_report(encode(proto::Command::kGetInfo, 7)));
  EXPECT_EQ(vc.led_mask(), 0);
  vc.plug_in();
  EXPECT_TRUE(vc.plugged_in());
  EXPECT_LT(vc.now_us(), 1'000'000u);  // clock restarted: a power cycle
  const auto status =
      payload_of<proto::StatusReply>(vc.request(encode(proto::Command::kGetStatus, 8)));
  EXPECT_EQ(status.codes_stored, 0x01);
  EXPECT_EQ(status.active_code_id, 0);
  EXPECT_TRUE(status.flags & proto::kStatusConfigFromFlash);
}

TEST(VirtualController, SavedFlashPageCarriesOverToANewController) {
  VirtualController first;
  arm_with_code(first);
  ASSERT_EQ(status_of(first.request(encode(proto::Command::kDisarm, 5))), proto::Status::kOk);
  ASSERT_EQ(status_of(first.request(encode(proto::Command::kSaveConfig, 6))), proto::Status::kOk);
  VirtualControllerOptions options;
  options.initial_flash_page = first.flash_page_contents();
  VirtualController second(options);
  const auto status =
      payload_of<proto::StatusReply>(second.request(encode(proto::Command::kGetStatus, 1)));
  EXPECT_TRUE(status.flags & proto::kStatusConfigFromFlash);
  EXPECT_EQ(status.codes_stored, 0x01);
  VirtualController fresh;
  const auto fresh_status =
      payload_of<proto::StatusReply>(fresh.request(encode(proto::Command::kGetStatus, 1)));
  EXPECT_EQ(fresh_status.codes_stored, 0);
}

TEST(VirtualController, EnterBootloaderTakesTheApplicationAway) {
  VirtualController vc;
  const Report reply =
      vc.request(encode(proto::Command::kEnterBootloader, 1,
                        proto::EnterBootloaderRequest{proto::kEnterBootloaderMagic}));
  EXPECT_EQ(status_of(reply), proto::Status::kOk);
  EXPECT_TRUE(vc.in_bootloader());
  EXPECT_FALSE(vc.write_report(encode(proto::Command::kGetInfo, 2)));
  vc.plug_in();
  EXPECT_FALSE(vc.in_bootloader());
  EXPECT_TRUE(vc.write_report(encode(proto::Command::kGetInfo, 3)));
}

TEST(VirtualController, SurvivesConcurrentRequestsAndExposures) {
  VirtualController vc;
  arm_with_code(vc);
  std::thread camera([&] {
    for (int i = 0; i < 200; ++i) {
      vc.expose(6000);
      vc.advance_us(4000);
    }
  });
  int events = 0;
  int replies = 0;
  for (int i = 0; i < 2000; ++i) {
    ASSERT_TRUE(vc.write_report(encode(proto::Command::kGetStatus, static_cast<std::uint8_t>(i))));
    while (const auto report = vc.read_report()) {
      if ((*report)[0] == static_cast<std::uint8_t>(proto::Command::kExposureEvent))
        ++events;
      else
        ++replies;
    }
  }
  camera.join();
  while (vc.read_report()) ++events;
  EXPECT_EQ(replies, 2000);
  const auto status =
      payload_of<proto::StatusReply>(vc.request(encode(proto::Command::kGetStatus, 1)));
  EXPECT_EQ(status.frame_counter, 200u);
  EXPECT_EQ(static_cast<std::uint32_t>(events) + status.events_dropped, 200u);
}

}  // namespace
}  // namespace flutterscan::device
