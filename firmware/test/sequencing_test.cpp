// The controller's exposures on the virtual clock: what the LEDs do and when.
#include <gtest/gtest.h>

#include <bit>

#include "sequence_check.hpp"
#include "test_rig.hpp"

namespace flutterscan::firmware::test {
namespace {

using proto::Command;
using proto::Status;

constexpr std::string_view kSeedMaxMin = "2212441414112412441224111241244244242212442211444144";
constexpr std::string_view kSeedAvgMin = "2212144111241224412411211221241444112124441212442242";

LedCode code3(std::string_view digits) {
  return LedCode::parse(digits, 3).value();
}

/// A rig armed in slave mode with `digits` as code 0 at `slot_us`.
void arm_slave(Rig& rig, std::string_view digits, std::uint32_t slot_us,
               proto::SlotTimeSource source = proto::SlotTimeSource::kFixed) {
  ASSERT_EQ(rig.upload(0, digits, 3), Status::kOk);
  ASSERT_EQ(rig.select(0), Status::kOk);
  ASSERT_EQ(rig.set_timing(slot_us, 0, source), Status::kOk);
  ASSERT_EQ(rig.arm(), Status::kOk);
}

TEST(Sequencing, OneOfThreeCodeLightsExactlyOneLedPerSlot) {
  Rig rig;
  arm_slave(rig, kSeedMaxMin, 100);
  rig.port.clear_led_transitions();
  rig.port.inject_strobe(1'000, 6'000);
  rig.port.run_until(20'000);
  const auto& log = rig.port.led_transitions();
  ASSERT_TRUE(plays_code(log, 0, code3(kSeedMaxMin), 1'000, 100));
  for (std::size_t i = 0; i + 1 < log.size(); ++i)
    EXPECT_EQ(std::popcount(static_cast<unsigned>(log[i].led_mask)), 1) << "slot " << i;
  EXPECT_EQ(log.back().led_mask, 0);
  const auto events = rig.events();
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].frame_counter, 1u);
  EXPECT_EQ(events[0].start_time_us, 1'000u);
  EXPECT_EQ(events[0].slot_time_us, 100u);
  EXPECT_EQ(events[0].slot_count, 52);
  EXPECT_EQ(events[0].code_id, 0);
  EXPECT_EQ(events[0].flags, 0);
  EXPECT_EQ(events[0].pulse_width_us, 0u);  // the pulse outlasted the sequence
}

TEST(Sequencing, AllLedsStayOffBetweenExposures) {
  Rig rig;
  arm_slave(rig, kSeedMaxMin, 50);
  rig.port.clear_led_transitions();
  for (int frame = 0; frame < 5; ++frame) rig.port.inject_strobe(10'000u * frame + 500, 3'000);
  rig.port.run_until(60'000);
  const auto& log = rig.port.led_transitions();
  ASSERT_EQ(log.size(), 5u * 53u);
  for (int frame = 0; frame < 5; ++frame) {
    const std::size_t first = static_cast<std::size_t>(frame) * 53;
    EXPECT_TRUE(plays_code(log, first, code3(kSeedMaxMin), 10'000u * frame + 500, 50));
    // The all-off word is the last write before the next exposure's first.
    EXPECT_EQ(log[first + 52].led_mask, 0);
  }
  EXPECT_EQ(rig.port.led_mask(), 0);
  EXPECT_EQ(rig.events().size(), 5u);
}

TEST(Sequencing, CodeSwitchTakesEffectAtTheNextExposureOnly) {
  Rig rig;
  ASSERT_EQ(rig.upload(1, kSeedAvgMin, 3), Status::kOk);
  arm_slave(rig, kSeedMaxMin, 100);
  rig.port.clear_led_transitions();
  rig.port.inject_strobe(1'000, 6'000);
  rig.port.inject_strobe(11'000, 6'000);
  rig.port.run_until(3'000);  // mid-exposure
  const auto reply = rig.send(Command::kSelectCode, proto::SelectCodeRequest{1, {}});
  ASSERT_EQ(reply.status(), Status::kOk);
  EXPECT_EQ(reply.as<proto::SelectCodeReply>().active_code_id, 0);
  EXPECT_EQ(reply.as<proto::SelectCodeReply>().pending_code_id, 1);
  EXPECT_EQ(rig.status().pending_code_id, 1);
  rig.port.run_until(30'000);
  const auto& log = rig.port.led_transitions();
  EXPECT_TRUE(plays_code(log, 0, code3(kSeedMaxMin), 1'000, 100));    // no glitch mid-sequence
  EXPECT_TRUE(plays_code(log, 53, code3(kSeedAvgMin), 11'000, 100));  // new code from frame 2
  const auto events = rig.events();
  ASSERT_EQ(events.size(), 2u);
  EXPECT_EQ(events[0].code_id, 0);
  EXPECT_EQ(events[0].flags & proto::kEventCodeSwitched, 0);
  EXPECT_EQ(events[1].code_id, 1);
  EXPECT_NE(events[1].flags & proto::kEventCodeSwitched, 0);
  EXPECT_EQ(rig.status().active_code_id, 1);
  EXPECT_EQ(rig.status().pending_code_id, proto::kNoCode);
}

TEST(Sequencing, SwitchingBackBeforeTheNextExposureCancelsTheSwitch) {
  Rig rig;
  ASSERT_EQ(rig.upload(1, kSeedAvgMin, 3), Status::kOk);
  arm_slave(rig, kSeedMaxMin, 100);
  ASSERT_EQ(rig.select(1), Status::kOk);
  ASSERT_EQ(rig.select(0), Status::kOk);
  rig.port.clear_led_transitions();
  rig.port.inject_strobe(1'000, 6'000);
  rig.port.run_until(10'000);
  EXPECT_TRUE(plays_code(rig.port.led_transitions(), 0, code3(kSeedMaxMin), 1'000, 100));
  EXPECT_EQ(rig.events().at(0).flags & proto::kEventCodeSwitched, 0);
}

TEST(Sequencing, SlaveSlotTimeFollowsThePulseWidthOverL) {
  Rig rig;
  arm_slave(rig, kSeedMaxMin, 50, proto::SlotTimeSource::kFollowExposure);
  rig.port.clear_led_transitions();
  // Camera exposes 5200 us: L = 52, so 100 us slots once a width is measured.
  rig.port.inject_strobe(1'000, 5'200);
  rig.port.inject_strobe(21'000, 5'200);
  rig.port.inject_strobe(41'000, 7'800);  // exposure changed: 150 us from the next frame
  rig.port.inject_strobe(61'000, 7'800);
  rig.port.run_until(80'000);
  const auto& log = rig.port.led_transitions();
  EXPECT_TRUE(plays_code(log, 0, code3(kSeedMaxMin), 1'000, 50));  // nothing measured yet
  EXPECT_TRUE(plays_code(log, 53, code3(kSeedMaxMin), 21'000, 100));
  EXPECT_TRUE(plays_code(log, 106, code3(kSeedMaxMin), 41'000, 100));
  EXPECT_TRUE(plays_code(log, 159, code3(kSeedMaxMin), 61'000, 150));
  const auto events = rig.events();
  ASSERT_EQ(events.size(), 4u);
  EXPECT_EQ(events[0].slot_time_us, 50u);
  EXPECT_EQ(events[1].slot_time_us, 100u);
  EXPECT_EQ(events[1].pulse_width_us, 0u);  // ended with the sequence, not before
  EXPECT_EQ(events[3].slot_time_us, 150u);
  for (const auto& e : events) EXPECT_EQ(e.flags & proto::kEventOverrun, 0);
}

TEST(Sequencing, FollowedSlotTimeIsClampedAndFlagged) {
  Rig rig;
  ASSERT_EQ(rig.send(Command::kSetGuard, permissive_guard()).status(), Status::kOk);
  arm_slave(rig, kSeedMaxMin, 10, proto::SlotTimeSource::kFollowExposure);
  rig.port.inject_strobe(1'000, 30);  // 30 us / 52 slots < 1 us
  rig.port.inject_strobe(2'000, 30);
  rig.port.run_until(5'000);
  const auto events = rig.events();
  ASSERT_EQ(events.size(), 2u);
  EXPECT_EQ(events[1].slot_time_us, 1u);
  EXPECT_NE(events[1].flags & proto::kEventSlotTimeClamped, 0);
}

TEST(Sequencing, EventCarriesTheEncoderDeltaDuringTheExposure) {
  Rig rig;
  arm_slave(rig, kSeedMaxMin, 100);
  rig.port.set_encoder_velocity(10'000);  // 10 counts per ms
  rig.port.inject_strobe(1'000, 6'000);
  rig.port.run_until(8'000);
  rig.port.set_encoder_velocity(-20'000);
  rig.port.inject_strobe(10'000, 6'000);
  rig.port.run_until(20'000);
  const auto events = rig.events();
  ASSERT_EQ(events.size(), 2u);
  EXPECT_EQ(events[0].encoder_delta, 52);    // 5.2 ms at 10 counts/ms
  EXPECT_EQ(events[1].encoder_delta, -104);  // 5.2 ms at -20 counts/ms
}

TEST(Sequencing, TriggerDuringAnExposureIsMissedAndFlagged) {
  Rig rig;
  arm_slave(rig, kSeedMaxMin, 100);
  rig.port.inject_strobe(1'000, 1'000);
  rig.port.inject_strobe(3'000, 1'000);  // while the 5.2 ms sequence still runs
  rig.port.run_until(10'000);
  const auto events = rig.events();
  ASSERT_EQ(events.size(), 1u);
  EXPECT_NE(events[0].flags & proto::kEventMissedTrigger, 0);
  EXPECT_NE(events[0].flags & proto::kEventOverrun, 0);  // the first pulse ended at 2 ms
  EXPECT_EQ(events[0].pulse_width_us, 1'000u);
  const auto status = rig.status();
  EXPECT_EQ(status.missed_triggers, 1u);
  EXPECT_EQ(status.overruns, 1u);
  EXPECT_EQ(status.frame_counter, 1u);
}

TEST(Sequencing, GuardRefusesAnExposureAndLeavesTheLedsOff) {
  Rig rig;
  // Longest run of kSeedMaxMin: "444" = 3 slots. 3 x 100 us allowed, 3 x 150 us not.
  proto::SetGuardRequest guard = permissive_guard();
  guard.max_on_time_us.fill(300);
  ASSERT_EQ(rig.send(Command::kSetGuard, guard).status(), Status::kOk);
  arm_slave(rig, kSeedMaxMin, 100, proto::SlotTimeSource::kFollowExposure);
  rig.port.clear_led_transitions();
  rig.port.inject_strobe(1'000, 7'800);   // lit at 100 us; measures 150 us slots
  rig.port.inject_strobe(21'000, 5'200);  // 150 us slots: refused, dark; measures 100 us
  rig.port.inject_strobe(41'000, 5'200);  // 100 us again: lit
  rig.port.run_until(60'000);
  const auto& log = rig.port.led_transitions();
  ASSERT_EQ(log.size(), 2u * 53u);
  EXPECT_TRUE(plays_code(log, 0, code3(kSeedMaxMin), 1'000, 100));
  EXPECT_TRUE(plays_code(log, 53, code3(kSeedMaxMin), 41'000, 100));
  const auto events = rig.events();
  ASSERT_EQ(events.size(), 3u);
  EXPECT_EQ(events[1].flags & proto::kEventGuardHit, proto::kEventGuardHit);
  EXPECT_EQ(events[1].slot_time_us, 150u);
  EXPECT_EQ(events[1].encoder_delta, 0);
  EXPECT_EQ(events[2].flags & proto::kEventGuardHit, 0);
  EXPECT_EQ(rig.status().guard_hits, 1u);
  EXPECT_EQ(rig.controller().state(), proto::ControllerState::kArmed);
}

TEST(Sequencing, GuardCapsTheDutyCycleOverTheMeasuredPeriod) {
  Rig rig;
  proto::SetGuardRequest guard = permissive_guard();
  guard.max_duty_permille.fill(200);  // LED 2 is on 21 of 52 slots: 2.1 ms per exposure
  ASSERT_EQ(rig.send(Command::kSetGuard, guard).status(), Status::kOk);
  arm_slave(rig, kSeedMaxMin, 100);
  rig.port.inject_strobe(1'000, 6'000);   // first: period unknown, lit
  rig.port.inject_strobe(21'000, 6'000);  // period 20 ms: 10.5 %, lit
  rig.port.inject_strobe(29'000, 6'000);  // period 8 ms: 26 %, refused
  rig.port.run_until(40'000);
  const auto events = rig.events();
  ASSERT_EQ(events.size(), 3u);
  EXPECT_EQ(events[0].flags & proto::kEventGuardHit, 0);
  EXPECT_EQ(events[1].flags & proto::kEventGuardHit, 0);
  EXPECT_NE(events[2].flags & proto::kEventGuardHit, 0);
  EXPECT_EQ(rig.port.led_transitions().back().time_us, 21'000u + 5'200u);
}

TEST(Sequencing, MasterModeTriggersTheCameraForTheExposure) {
  Rig rig;
  ASSERT_EQ(rig.upload(0, kSeedMaxMin, 3), Status::kOk);
  ASSERT_EQ(rig.select(0), Status::kOk);
  ASSERT_EQ(rig.set_mode(proto::SyncMode::kMaster), Status::kOk);
  ASSERT_EQ(rig.set_timing(100, 20'000), Status::kOk);
  rig.port.run_until(500);
  rig.port.clear_led_transitions();
  ASSERT_EQ(rig.arm(), Status::kOk);
  rig.port.run_until(46'000);
  const auto& triggers = rig.port.trigger_pulses();
  ASSERT_EQ(triggers.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(triggers[i].start_us, 500 + 20'000 * i);
    EXPECT_EQ(triggers[i].width_us, 5'200u);
    EXPECT_TRUE(plays_code(rig.port.led_transitions(), 53 * i, code3(kSeedMaxMin),
                           triggers[i].start_us, 100));
  }
  EXPECT_EQ(rig.events().size(), 3u);
}

TEST(Sequencing, FreeRunRepeatsWithoutTriggeringACamera) {
  Rig rig;
  ASSERT_EQ(rig.upload(0, "124", 3), Status::kOk);
  ASSERT_EQ(rig.select(0), Status::kOk);
  ASSERT_EQ(rig.set_mode(proto::SyncMode::kFreeRun), Status::kOk);
  ASSERT_EQ(rig.set_timing(1'000, 5'000), Status::kOk);
  rig.port.clear_led_transitions();
  ASSERT_EQ(rig.arm(), Status::kOk);
  rig.port.inject_strobe(2'500, 100);  // ignored outside slave mode
  rig.port.run_until(14'000);
  EXPECT_TRUE(rig.port.trigger_pulses().empty());
  for (std::size_t i = 0; i < 3; ++i)
    EXPECT_TRUE(plays_code(rig.port.led_transitions(), 4 * i, code3("124"), 5'000 * i, 1'000));
  EXPECT_EQ(rig.events().size(), 3u);
}

TEST(Sequencing, UsbResetMidExposureTurnsEverythingOff) {
  Rig rig;
  arm_slave(rig, kSeedMaxMin, 100);
  rig.port.inject_strobe(1'000, 6'000);
  rig.port.run_until(2'050);
  ASSERT_NE(rig.port.led_mask(), 0);
  rig.controller().on_usb_reset();
  EXPECT_EQ(rig.port.led_mask(), 0);
  EXPECT_FALSE(rig.port.slot_table_running());
  EXPECT_EQ(rig.controller().state(), proto::ControllerState::kIdle);
  const std::size_t writes = rig.port.led_transitions().size();
  rig.port.inject_strobe(10'000, 6'000);
  rig.port.run_until(20'000);
  EXPECT_EQ(rig.port.led_transitions().size(), writes);  // disarmed: strobes ignored
}

TEST(Sequencing, PortFaultTurnsEverythingOffUntilDisarm) {
  Rig rig;
  arm_slave(rig, kSeedMaxMin, 100);
  rig.port.inject_strobe(1'000, 6'000);
  rig.port.run_until(2'050);
  rig.controller().on_port_fault();
  EXPECT_EQ(rig.port.led_mask(), 0);
  auto status = rig.status();
  EXPECT_EQ(status.state, static_cast<std::uint8_t>(proto::ControllerState::kFault));
  EXPECT_EQ(status.last_fault, static_cast<std::uint8_t>(proto::FaultCode::kPort));
  EXPECT_EQ(rig.arm(), Status::kBadState);
  EXPECT_EQ(rig.disarm(), Status::kOk);
  EXPECT_EQ(rig.arm(), Status::kOk);
}

TEST(Sequencing, SlotTimerFailureIsAFault) {
  Rig rig;
  arm_slave(rig, kSeedMaxMin, 100);
  rig.port.set_slot_timer_fails(true);
  rig.port.inject_strobe(1'000, 6'000);
  rig.port.run_until(10'000);
  EXPECT_EQ(rig.controller().state(), proto::ControllerState::kFault);
  EXPECT_EQ(rig.status().last_fault, static_cast<std::uint8_t>(proto::FaultCode::kSlotTimer));
  EXPECT_EQ(rig.port.led_mask(), 0);
}

TEST(Sequencing, BootTurnsLedsOffAndReportsAWatchdogReset) {
  Rig rig(test_board(), false);
  rig.port.write_led_bank(0x00000007);  // whatever the LEDs did before the reset
  rig.port.set_reset_cause(ResetCause::kWatchdog);
  rig.controller().start();
  EXPECT_EQ(rig.port.led_mask(), 0);
  EXPECT_EQ(rig.status().last_fault, static_cast<std::uint8_t>(proto::FaultCode::kWatchdogReset));
  EXPECT_EQ(rig.controller().state(), proto::ControllerState::kIdle);
  rig.controller().poll();
  EXPECT_EQ(rig.port.watchdog_kicks(), 1);
}

TEST(Sequencing, UnreadEventsAreCountedWhenDropped) {
  Rig rig;
  arm_slave(rig, "124", 10);
  for (int i = 0; i < 20; ++i) rig.port.inject_strobe(1'000u * i + 100, 50);
  rig.port.run_until(30'000);
  EXPECT_EQ(rig.status().events_dropped, 4u);
  EXPECT_EQ(rig.events().size(), kEventQueueCapacity);
}

}  // namespace
}  // namespace flutterscan::firmware::test
