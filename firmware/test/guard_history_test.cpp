// The guard's history outlives Arm, Disarm, self tests and warm resets
// (issue 15, findings 1, 2 and 9): no host command sequence raises an LED's
// duty above its cap.
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "test_rig.hpp"

namespace flutterscan::firmware::test {
namespace {

using proto::Command;
using proto::Status;

/// A guard with a 10 % duty cap on every LED, on-time unlimited.
proto::SetGuardRequest ten_percent_guard() {
  proto::SetGuardRequest guard = permissive_guard();
  guard.max_duty_permille.fill(100);
  return guard;
}

// Finding 1: a host repeating SelfTest reached 32 % duty on LED 0 of a
// 3-LED board against a 10 % cap (only the step time was checked).
TEST(GuardHistory, RepeatedSelfTestsStayWithinTheDutyCap) {
  Rig rig;
  ASSERT_EQ(rig.send(Command::kSetGuard, ten_percent_guard()).status(), Status::kOk);
  rig.port.run_until(1'000);
  rig.port.clear_led_transitions();
  int accepted = 0;
  int refused = 0;
  for (int i = 0; i < 200; ++i) {
    const Status s = rig.send(Command::kSelfTest, proto::SelfTestRequest{1'000}).status();
    (s == Status::kOk ? accepted : refused) += 1;
    if (s != Status::kOk) {
      EXPECT_EQ(s, Status::kGuardLimit);
    }
    rig.port.run_for(3'001);  // the test is over: the next starts at once
  }
  const std::uint64_t end = rig.port.now_us();
  EXPECT_GT(accepted, 1);
  EXPECT_GT(refused, 0);
  for (int led = 0; led < 3; ++led)
    EXPECT_LE(on_time_us(rig.port.led_transitions(), led, 1'000, end) * 1000,
              100u * (end - 1'000) + 1'000u * 1000u)
        << "LED " << led;
}

// Finding 2: Disarm + Arm cleared the guard's history, and the first exposure
// after Arm had no duty check: 85.7 % duty in slave mode.
TEST(GuardHistory, DisarmAndArmDoNotResetTheDutyPeriod) {
  Rig rig;
  ASSERT_EQ(rig.send(Command::kSetGuard, ten_percent_guard()).status(), Status::kOk);
  ASSERT_EQ(rig.upload(0, "1110", 3), Status::kOk);  // LED 0 on 3 of 4 slots
  ASSERT_EQ(rig.select(0), Status::kOk);
  ASSERT_EQ(rig.set_timing(100, 0), Status::kOk);
  rig.port.run_until(1'000);
  rig.port.clear_led_transitions();
  int lit = 0;
  for (int i = 0; i < 50; ++i) {
    ASSERT_EQ(rig.arm(), Status::kOk);
    rig.port.inject_strobe(rig.port.now_us() + 10, 400);
    rig.port.run_for(460);
    const auto events = rig.events();
    ASSERT_EQ(events.size(), 1u);
    if ((events[0].flags & proto::kEventGuardHit) == 0) ++lit;
    ASSERT_EQ(rig.disarm(), Status::kOk);
  }
  const std::uint64_t end = rig.port.now_us();
  EXPECT_GE(lit, 1);
  // 300 us per lit exposure needs 3 ms since the last start.
  EXPECT_LE(on_time_us(rig.port.led_transitions(), 0, 1'000, end) * 1000,
            100u * (end - 1'000) + 300u * 1000u);
}

TEST(GuardHistory, DisarmAndArmInFreeRunDoNotResetTheDutyPeriod) {
  Rig rig;
  ASSERT_EQ(rig.send(Command::kSetGuard, ten_percent_guard()).status(), Status::kOk);
  ASSERT_EQ(rig.upload(0, "1000", 3), Status::kOk);  // 100 us on per 4 ms frame: 2.5 %
  ASSERT_EQ(rig.select(0), Status::kOk);
  ASSERT_EQ(rig.set_mode(proto::SyncMode::kFreeRun), Status::kOk);
  ASSERT_EQ(rig.set_timing(100, 4'000), Status::kOk);
  rig.port.run_until(1'000);
  rig.port.clear_led_transitions();
  // Re-arming every 200 us restarts the frame timer, whose first frame is at once.
  for (int i = 0; i < 50; ++i) {
    ASSERT_EQ(rig.arm(), Status::kOk);
    rig.port.run_for(200);
    ASSERT_EQ(rig.disarm(), Status::kOk);
  }
  const std::uint64_t end = rig.port.now_us();
  EXPECT_LE(on_time_us(rig.port.led_transitions(), 0, 1'000, end) * 1000,
            100u * (end - 1'000) + 100u * 1000u);
}

TEST(GuardHistory, ASelfTestCountsForTheNextExposure) {
  Rig rig;
  ASSERT_EQ(rig.send(Command::kSetGuard, ten_percent_guard()).status(), Status::kOk);
  ASSERT_EQ(rig.upload(0, "1", 3), Status::kOk);
  ASSERT_EQ(rig.select(0), Status::kOk);
  ASSERT_EQ(rig.set_timing(1'000, 0), Status::kOk);
  rig.port.run_until(1'000);
  ASSERT_EQ(rig.send(Command::kSelfTest, proto::SelfTestRequest{1'000}).status(), Status::kOk);
  rig.port.run_for(4'000);  // self test at 1000 us; LED 0 on 1000 us of it
  ASSERT_EQ(rig.arm(), Status::kOk);
  rig.port.inject_strobe(6'000, 500);   // 5 ms after the self test: 20 %, refused
  rig.port.inject_strobe(11'000, 500);  // 10 ms after it: lit
  rig.port.run_until(20'000);
  const auto events = rig.events();
  ASSERT_EQ(events.size(), 2u);
  EXPECT_NE(events[0].flags & proto::kEventGuardHit, 0);
  EXPECT_EQ(events[1].flags & proto::kEventGuardHit, 0);
}

TEST(GuardHistory, AWarmResetCountsTheDutyPeriodFromBoot) {
  Rig rig;
  ASSERT_EQ(rig.send(Command::kSetGuard, ten_percent_guard()).status(), Status::kOk);
  ASSERT_EQ(rig.send(Command::kSaveConfig).status(), Status::kOk);
  rig.port.run_until(1'000);
  // After a power-on reset the LEDs were cold: the first self test runs.
  ASSERT_EQ(rig.send(Command::kSelfTest, proto::SelfTestRequest{1'000}).status(), Status::kOk);
  rig.port.run_for(3'000);
  for (const ResetCause cause : {ResetCause::kWatchdog, ResetCause::kSoftware}) {
    rig.port.set_reset_cause(cause);
    rig.reboot();
    // The LEDs may have been on just before the reset: 1000 us needs 10 ms.
    EXPECT_EQ(rig.send(Command::kSelfTest, proto::SelfTestRequest{1'000}).status(),
              Status::kGuardLimit);
    rig.port.run_for(10'000);
    EXPECT_EQ(rig.send(Command::kSelfTest, proto::SelfTestRequest{1'000}).status(), Status::kOk);
    rig.port.run_for(3'000);
  }
}

// Finding 9: Arm cleared events and counters before the frame timer could fail.
TEST(GuardHistory, AFailedArmChangesNothing) {
  Rig rig;
  ASSERT_EQ(rig.upload(0, "1", 3), Status::kOk);
  ASSERT_EQ(rig.select(0), Status::kOk);
  ASSERT_EQ(rig.set_timing(100, 0), Status::kOk);
  ASSERT_EQ(rig.arm(), Status::kOk);
  rig.port.inject_strobe(1'000, 50);
  rig.port.run_until(2'000);
  ASSERT_EQ(rig.disarm(), Status::kOk);
  ASSERT_EQ(rig.set_mode(proto::SyncMode::kFreeRun), Status::kOk);
  ASSERT_EQ(rig.set_timing(100, 4'000), Status::kOk);
  const proto::StatusReply before = rig.status();
  ASSERT_EQ(before.frame_counter, 1u);
  rig.port.set_frame_timer_fails(true);
  EXPECT_EQ(rig.arm(), Status::kHardwareError);
  const proto::StatusReply after = rig.status();
  EXPECT_EQ(after.state, static_cast<std::uint8_t>(proto::ControllerState::kIdle));
  EXPECT_EQ(after.frame_counter, before.frame_counter);
  EXPECT_FALSE(rig.port.frame_timer_running());
  EXPECT_EQ(rig.events().size(), 1u);  // the event of the exposure before is still there
}

}  // namespace
}  // namespace flutterscan::firmware::test
