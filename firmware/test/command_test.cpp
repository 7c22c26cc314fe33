// Every command's happy path and every rejection; a rejection changes nothing.
#include <gtest/gtest.h>

#include "test_rig.hpp"

namespace flutterscan::firmware::test {
namespace {

using proto::Command;
using proto::Status;

constexpr std::string_view kSeedMaxMin = "2212441414112412441224111241244244242212442211444144";

/// Asserts that `send` gets `expected` and leaves settings and status as they were.
template <typename Send>
void expect_rejected_without_change(Rig& rig, Status expected, Send send) {
  const auto settings_before = rig.settings_snapshot();
  auto status_before = rig.status();
  const Reply reply = send();
  EXPECT_EQ(reply.status(), expected) << proto::status_text(reply.status());
  EXPECT_EQ(reply.header().payload_length, 0);
  EXPECT_EQ(rig.settings_snapshot(), settings_before);
  auto status_after = rig.status();
  status_before.uptime_us = status_after.uptime_us = 0;
  EXPECT_EQ(std::memcmp(&status_before, &status_after, sizeof(status_after)), 0);
}

proto::SetCodeRequest chunk(std::uint8_t id, std::string_view digits, std::uint16_t total,
                            std::uint16_t first, std::uint8_t leds = 3) {
  proto::SetCodeRequest r{};
  r.code_id = id;
  r.led_count = leds;
  r.total_slots = total;
  r.first_slot = first;
  r.slot_count = static_cast<std::uint8_t>(digits.size());
  for (std::size_t i = 0; i < digits.size(); ++i)
    r.masks[i] = static_cast<std::uint8_t>(digits[i] - '0');
  return r;
}

/// A rig with kSeedMaxMin as code 0, selected.
void with_code(Rig& rig) {
  ASSERT_EQ(rig.upload(0, kSeedMaxMin, 3), Status::kOk);
  ASSERT_EQ(rig.select(0), Status::kOk);
}

// --- framing ----------------------------------------------------------------

TEST(Commands, UnknownCommandIsRefusedAndEchoed) {
  Rig rig;
  for (const std::uint8_t number : {0x00, 0x0E, 0x7F, 0x80, 0xFF}) {
    std::array<std::uint8_t, proto::kReportSize> report{};
    report[0] = number;
    report[1] = 0x5A;
    const Reply reply = rig.send_raw(report);
    EXPECT_EQ(reply.status(), Status::kUnknownCommand) << int{number};
    EXPECT_EQ(reply.header().command, number);
    EXPECT_EQ(reply.header().sequence, 0x5A);
  }
}

TEST(Commands, MalformedReportsAreRefused) {
  Rig rig;
  with_code(rig);
  std::array<std::uint8_t, proto::kReportSize + 8> report{};
  report[0] = static_cast<std::uint8_t>(Command::kArm);
  report[1] = 3;
  expect_rejected_without_change(rig, Status::kBadLength,
                                 [&] { return rig.send_raw(std::span(report).first(2)); });
  expect_rejected_without_change(rig, Status::kBadLength, [&] { return rig.send_raw(report); });
  report[2] = 61;  // payload longer than a report holds
  expect_rejected_without_change(rig, Status::kBadLength, [&] {
    return rig.send_raw(std::span(report).first(proto::kReportSize));
  });
  report[2] = 0;
  report[3] = 1;  // reserved status byte
  expect_rejected_without_change(rig, Status::kBadHeader, [&] {
    return rig.send_raw(std::span(report).first(proto::kReportSize));
  });
  EXPECT_EQ(rig.controller().state(), proto::ControllerState::kIdle);
}

TEST(Commands, EveryCommandRefusesAWrongPayloadLength) {
  Rig rig;
  with_code(rig);
  for (std::uint8_t command = 0x01; command <= 0x0D; ++command) {
    for (const std::uint8_t length : {1, 3, 5, 59, 60}) {
      std::array<std::uint8_t, proto::kReportSize> report{};
      report[0] = command;
      report[2] = length;
      // Lengths that are right for the command are skipped.
      const bool right = (command == 0x02 && length == 60);
      if (right) continue;
      SCOPED_TRACE(testing::Message() << "command " << int{command} << " length " << int{length});
      expect_rejected_without_change(rig, Status::kBadLength, [&] { return rig.send_raw(report); });
    }
  }
}

// --- GetInfo / GetStatus ------------------------------------------------------

TEST(Commands, GetInfoReportsVersionsIdentityAndLimits) {
  Rig rig;
  const Reply reply = rig.send(Command::kGetInfo);
  ASSERT_EQ(reply.status(), Status::kOk);
  const auto info = reply.as<proto::InfoReply>();
  EXPECT_EQ(info.protocol_major, proto::kProtocolMajor);
  EXPECT_EQ(info.protocol_minor, proto::kProtocolMinor);
  EXPECT_EQ(info.firmware_major, 1);
  EXPECT_EQ(info.firmware_minor, 2);
  EXPECT_EQ(info.firmware_patch, 3);
  EXPECT_EQ(info.build_id, 0xC0FFEE01u);
  EXPECT_EQ(info.board_id, 0x0405);
  EXPECT_EQ(info.led_count, 3);
  EXPECT_EQ(info.max_codes, 8);
  EXPECT_EQ(info.max_slots, 256);
  EXPECT_EQ(info.min_slot_time_us, 1u);
  EXPECT_EQ(info.max_slot_time_us, 10'000u);
  EXPECT_NE(info.features & proto::kFeatureThermalGuard, 0u);
  EXPECT_EQ(info.features & proto::kFeatureDfu, 0u);  // no DFU interface yet
}

TEST(Commands, GetStatusReportsStateCodesAndCounters) {
  Rig rig;
  with_code(rig);
  ASSERT_EQ(rig.upload(6, "124", 3), Status::kOk);
  rig.port.run_until(12'345);
  const auto status = rig.status();
  EXPECT_EQ(status.state, static_cast<std::uint8_t>(proto::ControllerState::kIdle));
  EXPECT_EQ(status.active_code_id, 0);
  EXPECT_EQ(status.pending_code_id, proto::kNoCode);
  EXPECT_EQ(status.codes_stored, 0b0100'0001);
  EXPECT_EQ(status.slot_time_us, 100u);
  EXPECT_EQ(status.uptime_us, 12'345u);
  EXPECT_EQ(status.flags, 0);  // empty flash: defaults, not corrupt
  EXPECT_EQ(status.last_fault, 0);
}

// --- SetCode ------------------------------------------------------------------

TEST(Commands, SetCodeStoresACodeInOneChunk) {
  Rig rig;
  const Reply reply = rig.send(Command::kSetCode, chunk(2, "1241", 4, 0));
  ASSERT_EQ(reply.status(), Status::kOk);
  EXPECT_EQ(reply.as<proto::SetCodeReply>().slots_received, 4);
  EXPECT_EQ(reply.as<proto::SetCodeReply>().complete, 1);
  const auto& stored = rig.controller().settings().codes[2];
  ASSERT_TRUE(stored.present);
  EXPECT_EQ(stored.code, LedCode::parse("1241", 3).value());
}

TEST(Commands, SetCodeAssemblesChunksInOrder) {
  Rig rig;
  auto reply = rig.send(Command::kSetCode, chunk(1, "12", 5, 0));
  ASSERT_EQ(reply.status(), Status::kOk);
  EXPECT_EQ(reply.as<proto::SetCodeReply>().complete, 0);
  EXPECT_FALSE(rig.controller().settings().codes[1].present);
  EXPECT_NE(rig.status().flags & proto::kStatusUploadInProgress, 0);
  expect_rejected_without_change(rig, Status::kOutOfOrder,
                                 [&] { return rig.send(Command::kSetCode, chunk(1, "4", 5, 3)); });
  expect_rejected_without_change(rig, Status::kOutOfOrder,
                                 [&] { return rig.send(Command::kSetCode, chunk(2, "4", 5, 2)); });
  expect_rejected_without_change(rig, Status::kOutOfOrder,
                                 [&] { return rig.send(Command::kSetCode, chunk(1, "4", 6, 2)); });
  reply = rig.send(Command::kSetCode, chunk(1, "412", 5, 2));
  ASSERT_EQ(reply.status(), Status::kOk);
  EXPECT_EQ(reply.as<proto::SetCodeReply>().slots_received, 5);
  EXPECT_EQ(rig.controller().settings().codes[1].code, LedCode::parse("12412", 3).value());
  EXPECT_EQ(rig.status().flags & proto::kStatusUploadInProgress, 0);
}

TEST(Commands, SetCodeRejectsOutOfRangeArguments) {
  Rig rig;
  with_code(rig);
  auto reject = [&](Status expected, proto::SetCodeRequest r) {
    expect_rejected_without_change(rig, expected, [&] { return rig.send(Command::kSetCode, r); });
  };
  reject(Status::kOutOfRange, chunk(8, "124", 3, 0));     // no such slot
  reject(Status::kOutOfRange, chunk(0, "124", 3, 0, 4));  // board has 3 LEDs
  reject(Status::kOutOfRange, chunk(0, "124", 3, 0, 0));  // no LEDs
  reject(Status::kOutOfRange, chunk(0, "124", 0, 0));     // no slots
  reject(Status::kOutOfRange, chunk(0, "124", 257, 0));   // too long
  reject(Status::kOutOfRange, chunk(0, "124", 2, 0));     // chunk beyond the total
  reject(Status::kOutOfRange, chunk(0, "", 3, 0));        // empty chunk
  auto too_many = chunk(0, "1", 100, 0);
  too_many.slot_count = 53;
  reject(Status::kOutOfRange, too_many);
  auto flags = chunk(0, "124", 3, 0);
  flags.flags = 0x02;
  reject(Status::kOutOfRange, flags);
  reject(Status::kBadCode, chunk(0, "128", 3, 0));  // LED 3 on a 3-LED code
  reject(Status::kBadCode, chunk(0, "18", 5, 0));   // ... also in a first chunk
  auto one_of_n = chunk(0, "1234", 4, 0);
  one_of_n.flags = proto::kCodeFlagOneOfN;
  reject(Status::kBadCode, one_of_n);
  EXPECT_EQ(rig.controller().settings().codes[0].code, LedCode::parse(kSeedMaxMin, 3).value());
}

TEST(Commands, SetCodeRefusesTheCodeInUseWhileArmed) {
  Rig rig;
  with_code(rig);
  ASSERT_EQ(rig.upload(1, "124", 3), Status::kOk);
  ASSERT_EQ(rig.arm(), Status::kOk);
  expect_rejected_without_change(
      rig, Status::kBadState, [&] { return rig.send(Command::kSetCode, chunk(0, "421", 3, 0)); });
  ASSERT_EQ(rig.select(1), Status::kOk);  // pending
  expect_rejected_without_change(
      rig, Status::kBadState, [&] { return rig.send(Command::kSetCode, chunk(1, "421", 3, 0)); });
  EXPECT_EQ(rig.send(Command::kSetCode, chunk(2, "421", 3, 0)).status(), Status::kOk);
}

// --- SelectCode -----------------------------------------------------------------

TEST(Commands, SelectCodeRejections) {
  Rig rig;
  with_code(rig);
  auto reject = [&](Status expected, proto::SelectCodeRequest r) {
    expect_rejected_without_change(rig, expected,
                                   [&] { return rig.send(Command::kSelectCode, r); });
  };
  reject(Status::kNoSuchCode, {3, {}});
  reject(Status::kOutOfRange, {8, {}});
  reject(Status::kOutOfRange, {0, {0, 1, 0}});
}

TEST(Commands, SelectCodeWhileArmedChecksTheGuardAndFramePeriod) {
  Rig rig;
  with_code(rig);
  ASSERT_EQ(rig.upload(1, "1111111111", 3), Status::kOk);
  ASSERT_EQ(rig.upload(2, std::string(200, '1'), 3), Status::kOk);
  ASSERT_EQ(rig.set_mode(proto::SyncMode::kFreeRun), Status::kOk);
  ASSERT_EQ(rig.set_timing(100, 10'000), Status::kOk);
  proto::SetGuardRequest guard = permissive_guard();
  guard.max_on_time_us.fill(500);
  ASSERT_EQ(rig.send(Command::kSetGuard, guard).status(), Status::kOk);
  ASSERT_EQ(rig.arm(), Status::kOk);
  expect_rejected_without_change(rig, Status::kGuardLimit, [&] {
    return rig.send(Command::kSelectCode, proto::SelectCodeRequest{1, {}});
  });
  expect_rejected_without_change(rig, Status::kTimingConflict, [&] {
    return rig.send(Command::kSelectCode, proto::SelectCodeRequest{2, {}});
  });
}

// --- SetTiming / SetMode / SetBrightness / SetGuard ---------------------------------

TEST(Commands, SetTimingHappyPathAndRejections) {
  Rig rig;
  ASSERT_EQ(rig.set_timing(250, 40'000, proto::SlotTimeSource::kFollowExposure), Status::kOk);
  const TimingSettings& timing = rig.controller().settings().timing;
  EXPECT_EQ(timing.slot_time_us, 250u);
  EXPECT_EQ(timing.frame_period_us, 40'000u);
  EXPECT_EQ(timing.source, proto::SlotTimeSource::kFollowExposure);
  auto reject = [&](Status expected, proto::SetTimingRequest r) {
    expect_rejected_without_change(rig, expected, [&] { return rig.send(Command::kSetTiming, r); });
  };
  reject(Status::kOutOfRange, {0, 0, 0, {}});
  reject(Status::kOutOfRange, {10'001, 0, 0, {}});
  reject(Status::kOutOfRange, {100, 999, 0, {}});
  reject(Status::kOutOfRange, {100, 10'000'001, 0, {}});
  reject(Status::kOutOfRange, {100, 0, 2, {}});
  reject(Status::kOutOfRange, {100, 0, 0, {0, 0, 1}});
  EXPECT_EQ(rig.set_timing(1), Status::kOk);
  EXPECT_EQ(rig.set_timing(10'000, 10'000'000), Status::kOk);
  with_code(rig);
  ASSERT_EQ(rig.set_timing(100), Status::kOk);
  ASSERT_EQ(rig.arm(), Status::kOk);
  reject(Status::kBadState, {100, 0, 0, {}});
}

TEST(Commands, SetModeHappyPathAndRejections) {
  Rig rig;
  ASSERT_EQ(rig.send(Command::kSetMode, proto::SetModeRequest{1, 1, {}}).status(), Status::kOk);
  EXPECT_EQ(rig.controller().settings().mode.sync, proto::SyncMode::kMaster);
  EXPECT_TRUE(rig.controller().settings().mode.strobe_active_low);
  auto reject = [&](Status expected, proto::SetModeRequest r) {
    expect_rejected_without_change(rig, expected, [&] { return rig.send(Command::kSetMode, r); });
  };
  reject(Status::kOutOfRange, {3, 0, {}});
  reject(Status::kOutOfRange, {0, 2, {}});
  reject(Status::kOutOfRange, {0, 0, {1, 0}});
  ASSERT_EQ(rig.set_mode(proto::SyncMode::kSlave), Status::kOk);
  with_code(rig);
  ASSERT_EQ(rig.arm(), Status::kOk);
  reject(Status::kBadState, {2, 0, {}});
}

TEST(Commands, StrobePolarityReachesThePortOnArm) {
  Rig rig;
  with_code(rig);
  ASSERT_EQ(rig.send(Command::kSetMode, proto::SetModeRequest{0, 1, {}}).status(), Status::kOk);
  ASSERT_EQ(rig.arm(), Status::kOk);
  EXPECT_TRUE(rig.port.strobe_active_low());
}

TEST(Commands, SetBrightnessAppliesAtOnceAndRejectsOverFullScale) {
  Rig rig;
  EXPECT_EQ(rig.port.led_brightness(1), 1000);  // applied at start
  ASSERT_EQ(
      rig.send(Command::kSetBrightness, proto::SetBrightnessRequest{{100, 200, 300, 0}}).status(),
      Status::kOk);
  EXPECT_EQ(rig.port.led_brightness(0), 100);
  EXPECT_EQ(rig.port.led_brightness(2), 300);
  expect_rejected_without_change(rig, Status::kOutOfRange, [&] {
    return rig.send(Command::kSetBrightness, proto::SetBrightnessRequest{{1, 1001, 1, 0}});
  });
  EXPECT_EQ(rig.port.led_brightness(0), 100);
  // Allowed while armed.
  with_code(rig);
  ASSERT_EQ(rig.arm(), Status::kOk);
  EXPECT_EQ(rig.send(Command::kSetBrightness, proto::SetBrightnessRequest{{5, 5, 5, 0}}).status(),
            Status::kOk);
  EXPECT_EQ(rig.port.led_brightness(1), 5);
}

TEST(Commands, SetGuardHappyPathAndRejections) {
  Rig rig;
  proto::SetGuardRequest guard{{1'000, 2'000, 3'000, 0}, {100, 200, 300, 0}};
  ASSERT_EQ(rig.send(Command::kSetGuard, guard).status(), Status::kOk);
  EXPECT_EQ(rig.controller().settings().guard.max_on_time_us[1], 2'000u);
  EXPECT_EQ(rig.controller().settings().guard.max_duty_permille[2], 300);
  auto reject = [&](Status expected, proto::SetGuardRequest r) {
    expect_rejected_without_change(rig, expected, [&] { return rig.send(Command::kSetGuard, r); });
  };
  reject(Status::kOutOfRange, {{0, 1, 1, 0}, {1, 1, 1, 0}});
  reject(Status::kOutOfRange, {{1, 1, proto::kMaxGuardOnTimeUs + 1, 0}, {1, 1, 1, 0}});
  reject(Status::kOutOfRange, {{1, 1, 1, 0}, {1, 0, 1, 0}});
  reject(Status::kOutOfRange, {{1, 1, 1, 0}, {1, 1, 1001, 0}});
  ASSERT_EQ(rig.send(Command::kSetGuard, permissive_guard()).status(), Status::kOk);
  with_code(rig);
  ASSERT_EQ(rig.arm(), Status::kOk);
  reject(Status::kBadState, permissive_guard());
}

// --- Arm / Disarm -------------------------------------------------------------------

TEST(Commands, ArmAndDisarm) {
  Rig rig;
  with_code(rig);
  ASSERT_EQ(rig.arm(), Status::kOk);
  EXPECT_EQ(rig.status().state, static_cast<std::uint8_t>(proto::ControllerState::kArmed));
  expect_rejected_without_change(rig, Status::kBadState, [&] { return rig.send(Command::kArm); });
  rig.port.inject_strobe(rig.port.now_us() + 10, 6'000);
  rig.port.run_for(1'000);
  EXPECT_EQ(rig.status().state, static_cast<std::uint8_t>(proto::ControllerState::kExposing));
  EXPECT_NE(rig.port.led_mask(), 0);
  ASSERT_EQ(rig.disarm(), Status::kOk);
  EXPECT_EQ(rig.port.led_mask(), 0);
  EXPECT_FALSE(rig.port.slot_table_running());
  EXPECT_EQ(rig.status().state, static_cast<std::uint8_t>(proto::ControllerState::kIdle));
  EXPECT_EQ(rig.disarm(), Status::kOk);  // disarming twice is fine
}

TEST(Commands, ArmRejections) {
  Rig rig;
  expect_rejected_without_change(rig, Status::kNoSuchCode, [&] { return rig.send(Command::kArm); });
  with_code(rig);
  ASSERT_EQ(rig.set_mode(proto::SyncMode::kMaster), Status::kOk);
  expect_rejected_without_change(rig, Status::kTimingConflict,
                                 [&] { return rig.send(Command::kArm); });
  ASSERT_EQ(rig.set_timing(100, 5'000), Status::kOk);  // 5.2 ms exposure > 5 ms period
  expect_rejected_without_change(rig, Status::kTimingConflict,
                                 [&] { return rig.send(Command::kArm); });
  ASSERT_EQ(rig.set_timing(100, 6'000), Status::kOk);  // LED 2: 2.1 ms of 6 ms > 30 %
  proto::SetGuardRequest guard = permissive_guard();
  guard.max_duty_permille.fill(300);
  ASSERT_EQ(rig.send(Command::kSetGuard, guard).status(), Status::kOk);
  expect_rejected_without_change(rig, Status::kGuardLimit, [&] { return rig.send(Command::kArm); });
  EXPECT_FALSE(rig.port.frame_timer_running());
  ASSERT_EQ(rig.set_timing(100, 8'000), Status::kOk);
  EXPECT_EQ(rig.arm(), Status::kOk);
  EXPECT_TRUE(rig.port.frame_timer_running());
}

// --- SelfTest ---------------------------------------------------------------------------

TEST(Commands, SelfTestStepsEachLedOnce) {
  Rig rig;
  rig.port.run_until(1'000);
  rig.port.clear_led_transitions();
  const Reply reply = rig.send(Command::kSelfTest, proto::SelfTestRequest{2'000});
  ASSERT_EQ(reply.status(), Status::kOk);
  EXPECT_EQ(reply.as<proto::SelfTestReply>().leds_stepped, 3);
  EXPECT_EQ(reply.as<proto::SelfTestReply>().duration_us, 6'000u);
  EXPECT_NE(rig.status().flags & proto::kStatusSelfTestRunning, 0);
  expect_rejected_without_change(rig, Status::kBusy, [&] {
    return rig.send(Command::kSelfTest, proto::SelfTestRequest{2'000});
  });
  rig.port.run_until(10'000);
  const auto& log = rig.port.led_transitions();
  ASSERT_EQ(log.size(), 4u);
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(log[i].time_us, 1'000 + 2'000 * i);
    EXPECT_EQ(log[i].led_mask, i < 3 ? (1u << i) : 0u);
  }
  EXPECT_EQ(rig.status().flags & proto::kStatusSelfTestRunning, 0);
  EXPECT_TRUE(rig.events().empty());
}

TEST(Commands, SelfTestRejections) {
  Rig rig;
  auto reject = [&](Status expected, std::uint32_t step) {
    expect_rejected_without_change(
        rig, expected, [&] { return rig.send(Command::kSelfTest, proto::SelfTestRequest{step}); });
  };
  reject(Status::kOutOfRange, 0);
  reject(Status::kOutOfRange, 10'001);
  proto::SetGuardRequest guard = permissive_guard();
  guard.max_on_time_us[1] = 500;
  ASSERT_EQ(rig.send(Command::kSetGuard, guard).status(), Status::kOk);
  reject(Status::kGuardLimit, 501);
  with_code(rig);
  ASSERT_EQ(rig.arm(), Status::kOk);
  reject(Status::kBadState, 100);
  EXPECT_TRUE(rig.port.led_transitions().empty() || rig.port.led_mask() == 0);
}

// --- SaveConfig / EnterBootloader ----------------------------------------------------------

TEST(Commands, SaveConfigWritesFlash) {
  Rig rig;
  with_code(rig);
  const Reply reply = rig.send(Command::kSaveConfig);
  ASSERT_EQ(reply.status(), Status::kOk);
  EXPECT_EQ(reply.as<proto::SaveConfigReply>().bytes_written, sizeof(ConfigImage));
  EXPECT_EQ(reply.as<proto::SaveConfigReply>().crc32,
            encode_config(rig.controller().settings()).crc32);
  EXPECT_EQ(rig.port.flash_erases(), 1);
}

TEST(Commands, SaveConfigRejections) {
  Rig rig;
  with_code(rig);
  rig.port.set_flash_fails(true);
  EXPECT_EQ(rig.send(Command::kSaveConfig).status(), Status::kFlashError);
  rig.port.set_flash_fails(false);
  ASSERT_EQ(rig.arm(), Status::kOk);
  expect_rejected_without_change(rig, Status::kBadState,
                                 [&] { return rig.send(Command::kSaveConfig); });
  EXPECT_EQ(rig.port.flash_erases(), 0);
}

TEST(Commands, EnterBootloaderNeedsTheMagicAndTurnsLedsOff) {
  Rig rig;
  with_code(rig);
  ASSERT_EQ(rig.arm(), Status::kOk);
  expect_rejected_without_change(rig, Status::kOutOfRange, [&] {
    return rig.send(Command::kEnterBootloader, proto::EnterBootloaderRequest{0x12345678});
  });
  rig.controller().poll();
  EXPECT_EQ(rig.port.bootloader_entries(), 0);
  ASSERT_EQ(rig.send(Command::kEnterBootloader,
                     proto::EnterBootloaderRequest{proto::kEnterBootloaderMagic})
                .status(),
            Status::kOk);
  EXPECT_EQ(rig.controller().state(), proto::ControllerState::kIdle);
  EXPECT_EQ(rig.port.led_mask(), 0);
  EXPECT_EQ(rig.port.bootloader_entries(), 0);  // not before the reply has gone out
  rig.controller().poll();
  rig.controller().poll();
  EXPECT_EQ(rig.port.bootloader_entries(), 1);
}

// --- events -------------------------------------------------------------------------------

TEST(Commands, ExposureEventsBecomeReports) {
  Rig rig;
  with_code(rig);
  ASSERT_EQ(rig.arm(), Status::kOk);
  rig.port.inject_strobe(1'000, 6'000);
  rig.port.run_until(10'000);
  std::array<std::uint8_t, proto::kReportSize> report{};
  ASSERT_EQ(rig.handler().next_event_report(report), proto::kReportSize);
  const auto message = proto::parse_message(report);
  ASSERT_TRUE(message.ok());
  EXPECT_EQ(message.value().header.command, static_cast<std::uint8_t>(Command::kExposureEvent));
  const auto event = proto::decode_payload<proto::ExposureEvent>(message.value().payload);
  ASSERT_TRUE(event.ok());
  EXPECT_EQ(event.value().start_time_us, 1'000u);
  EXPECT_EQ(rig.handler().next_event_report(report), 0u);
}

}  // namespace
}  // namespace flutterscan::firmware::test
