// The controller's exposures on the virtual clock: what the LEDs do and when.
#include <gtest/gtest.h>

#include <algorithm>
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

/// Longest time LED `led` stays on in `log`, in us; a run that ends and restarts
/// in the same microsecond is one run (the LED never visibly turns off).
std::uint64_t longest_on_us(const std::vector<sim::LedTransition>& log, int led) {
  std::uint64_t longest = 0;
  bool on = false;
  std::uint64_t since = 0;
  for (std::size_t i = 0; i < log.size(); ++i) {
    // Only the level after the last write of each microsecond counts.
    if (i + 1 < log.size() && log[i + 1].time_us == log[i].time_us) continue;
    const bool now_on = ((log[i].led_mask >> led) & 1u) != 0;
    if (now_on && !on) since = log[i].time_us;
    if (!now_on && on) longest = std::max(longest, log[i].time_us - since);
    on = now_on;
  }
  return longest;
}

/// Which of `events` report that the guard refused their exposure, in order.
std::vector<bool> guard_hits(const std::vector<proto::ExposureEvent>& events) {
  std::vector<bool> hits;
  for (const auto& e : events) hits.push_back((e.flags & proto::kEventGuardHit) != 0);
  return hits;
}

/// A guard allowing everything but `on_us` of continuous on-time per LED.
proto::SetGuardRequest on_time_guard(std::uint32_t on_us) {
  proto::SetGuardRequest guard = permissive_guard();
  guard.max_on_time_us.fill(on_us);
  return guard;
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
  EXPECT_EQ(guard_hits(events), (std::vector<bool>{false, false, true}));
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

// ---------------------------------------------------------------------------
// The guard across back-to-back exposures of different codes or slot times
// (firmware/fuzz/crashes/guard-*).

TEST(SequencingGuardSeam, FreeRunCodeSwitchCannotJoinRunsPastTheLimit) {
  Rig rig;
  ASSERT_EQ(rig.send(Command::kSetGuard, on_time_guard(750)).status(), Status::kOk);
  ASSERT_EQ(rig.upload(0, "0111", 1), Status::kOk);  // wraps into itself: 750 us, allowed
  ASSERT_EQ(rig.upload(1, "1000", 1), Status::kOk);
  ASSERT_EQ(rig.select(0), Status::kOk);
  ASSERT_EQ(rig.set_mode(proto::SyncMode::kFreeRun), Status::kOk);
  ASSERT_EQ(rig.set_timing(250, 1'000), Status::kOk);  // back to back
  rig.port.clear_led_transitions();
  ASSERT_EQ(rig.arm(), Status::kOk);
  rig.port.run_until(1'500);
  ASSERT_EQ(rig.select(1), Status::kOk);  // takes over at 2000 us, where 0111's run ends
  rig.port.run_until(5'500);
  const auto& log = rig.port.led_transitions();
  EXPECT_LE(longest_on_us(log, 0), 750u);
  const auto events = rig.events();
  ASSERT_EQ(events.size(), 5u);
  EXPECT_EQ(events[1].flags & proto::kEventGuardHit, 0);
  EXPECT_EQ(events[2].start_time_us, 2'000u);
  EXPECT_EQ(events[2].code_id, 1);
  EXPECT_NE(events[2].flags & proto::kEventGuardHit, 0);
  // The refused exposure stayed dark: nothing written between 0111's end and 3000 us.
  for (const auto& t : log)
    if (t.time_us > 2'000 && t.time_us < 3'000) ADD_FAILURE() << "LED write at " << t.time_us;
  // After the dark exposure code 1 plays, and repeats back to back.
  EXPECT_EQ(events[3].flags & proto::kEventGuardHit, 0);
  EXPECT_EQ(events[4].flags & proto::kEventGuardHit, 0);
  EXPECT_EQ(rig.status().guard_hits, 1u);
  EXPECT_EQ(rig.controller().state(), proto::ControllerState::kExposing);  // still sequencing
}

TEST(SequencingGuardSeam, SlaveFollowExposureSlotChangeCannotJoinRunsPastTheLimit) {
  Rig rig;
  ASSERT_EQ(rig.send(Command::kSetGuard, on_time_guard(200)).status(), Status::kOk);
  ASSERT_EQ(rig.upload(0, "1011", 1), Status::kOk);
  ASSERT_EQ(rig.select(0), Status::kOk);
  ASSERT_EQ(rig.set_timing(100, 0, proto::SlotTimeSource::kFollowExposure), Status::kOk);
  ASSERT_EQ(rig.arm(), Status::kOk);
  rig.port.clear_led_transitions();
  rig.port.inject_strobe(1'000, 200);  // 100 us slots until 1400 us; measures 50 us slots
  rig.port.inject_strobe(1'400, 200);  // starts as the first ends: 200 + 50 us on, refused
  rig.port.inject_strobe(3'000, 200);  // apart: lit at 50 us
  rig.port.run_until(5'000);
  const auto& log = rig.port.led_transitions();
  EXPECT_LE(longest_on_us(log, 0), 200u);
  ASSERT_EQ(log.size(), 10u);
  EXPECT_TRUE(plays_code(log, 0, LedCode::parse("1011", 1).value(), 1'000, 100));
  EXPECT_TRUE(plays_code(log, 5, LedCode::parse("1011", 1).value(), 3'000, 50));
  const auto events = rig.events();
  ASSERT_EQ(events.size(), 3u);
  EXPECT_EQ(events[0].flags & proto::kEventGuardHit, 0);
  EXPECT_NE(events[1].flags & proto::kEventGuardHit, 0);
  EXPECT_EQ(events[1].slot_time_us, 50u);
  EXPECT_EQ(events[2].flags & proto::kEventGuardHit, 0);
  EXPECT_EQ(rig.status().guard_hits, 1u);
}

TEST(SequencingGuardSeam, SlaveFixedSlotCodeSwitchCannotJoinRunsPastTheLimit) {
  Rig rig;
  ASSERT_EQ(rig.send(Command::kSetGuard, on_time_guard(750)).status(), Status::kOk);
  ASSERT_EQ(rig.upload(0, "0111", 1), Status::kOk);
  ASSERT_EQ(rig.upload(1, "1000", 1), Status::kOk);
  ASSERT_EQ(rig.select(0), Status::kOk);
  ASSERT_EQ(rig.set_timing(250), Status::kOk);
  ASSERT_EQ(rig.arm(), Status::kOk);
  rig.port.clear_led_transitions();
  rig.port.inject_strobe(1'000, 100);
  rig.port.inject_strobe(2'000, 100);  // back to back with itself: 750 us, allowed
  rig.port.run_until(2'500);
  ASSERT_EQ(rig.select(1), Status::kOk);
  rig.port.inject_strobe(3'000, 100);  // code 1 right after 0111: 1000 us, refused
  rig.port.inject_strobe(4'000, 100);  // after a dark exposure: lit
  rig.port.run_until(6'000);
  const auto& log = rig.port.led_transitions();
  EXPECT_LE(longest_on_us(log, 0), 750u);
  const auto events = rig.events();
  ASSERT_EQ(guard_hits(events), (std::vector<bool>{false, false, true, false}));
  EXPECT_EQ(events[2].code_id, 1);
  ASSERT_EQ(log.size(), 15u);  // three lit exposures of 5 writes
  EXPECT_TRUE(plays_code(log, 10, LedCode::parse("1000", 1).value(), 4'000, 250));
}

TEST(SequencingGuardSeam, BackToBackSwitchesWithinTheLimitStillPlay) {
  Rig rig;
  ASSERT_EQ(rig.send(Command::kSetGuard, on_time_guard(750)).status(), Status::kOk);
  ASSERT_EQ(rig.upload(0, "0011", 1), Status::kOk);  // 500 us trailing
  ASSERT_EQ(rig.upload(1, "1000", 1), Status::kOk);  // + 250 us leading = 750 us
  ASSERT_EQ(rig.select(0), Status::kOk);
  ASSERT_EQ(rig.set_mode(proto::SyncMode::kFreeRun), Status::kOk);
  ASSERT_EQ(rig.set_timing(250, 1'000), Status::kOk);
  rig.port.clear_led_transitions();
  ASSERT_EQ(rig.arm(), Status::kOk);
  rig.port.run_until(1'500);
  ASSERT_EQ(rig.select(1), Status::kOk);
  rig.port.run_until(2'500);
  ASSERT_EQ(rig.select(0), Status::kOk);
  rig.port.run_until(6'500);
  const auto& log = rig.port.led_transitions();
  EXPECT_EQ(longest_on_us(log, 0), 750u);  // 1500..2250: joined, at the limit
  const auto events = rig.events();
  ASSERT_EQ(events.size(), 6u);
  for (const auto& e : events) EXPECT_EQ(e.flags & proto::kEventGuardHit, 0) << e.frame_counter;
  EXPECT_EQ(rig.status().guard_hits, 0u);
  EXPECT_TRUE(plays_code(log, 10, LedCode::parse("1000", 1).value(), 2'000, 250));
}

TEST(SequencingGuardSeam, SlaveSlotChangeWithinTheLimitStillPlays) {
  Rig rig;
  ASSERT_EQ(rig.send(Command::kSetGuard, on_time_guard(250)).status(), Status::kOk);
  ASSERT_EQ(rig.upload(0, "1011", 1), Status::kOk);
  ASSERT_EQ(rig.select(0), Status::kOk);
  ASSERT_EQ(rig.set_timing(100, 0, proto::SlotTimeSource::kFollowExposure), Status::kOk);
  ASSERT_EQ(rig.arm(), Status::kOk);
  rig.port.clear_led_transitions();
  rig.port.inject_strobe(1'000, 200);  // 100 us slots; measures 50 us
  rig.port.inject_strobe(1'400, 200);  // 200 + 50 = 250 us at the seam: allowed
  rig.port.run_until(3'000);
  const auto& log = rig.port.led_transitions();
  EXPECT_EQ(longest_on_us(log, 0), 250u);
  const auto events = rig.events();
  ASSERT_EQ(events.size(), 2u);
  EXPECT_EQ(events[1].flags & proto::kEventGuardHit, 0);
  EXPECT_TRUE(plays_code(log, 5, LedCode::parse("1011", 1).value(), 1'400, 50));
}

TEST(SequencingGuardSeam, AnLedOnThroughoutCarriesItsRunIntoTheNextSeam) {
  Rig rig;
  ASSERT_EQ(rig.send(Command::kSetGuard, on_time_guard(2'500)).status(), Status::kOk);
  ASSERT_EQ(rig.upload(0, "1111", 1), Status::kOk);  // wraps into itself: 1000 us per check
  ASSERT_EQ(rig.select(0), Status::kOk);
  ASSERT_EQ(rig.set_mode(proto::SyncMode::kFreeRun), Status::kOk);
  ASSERT_EQ(rig.set_timing(250, 1'000), Status::kOk);
  rig.port.clear_led_transitions();
  ASSERT_EQ(rig.arm(), Status::kOk);
  rig.port.run_until(4'500);
  EXPECT_LE(longest_on_us(rig.port.led_transitions(), 0), 2'500u);
  const auto events = rig.events();
  ASSERT_EQ(events.size(), 4u);
  EXPECT_EQ(events[1].flags & proto::kEventGuardHit, 0);  // 2000 us so far
  EXPECT_NE(events[2].flags & proto::kEventGuardHit, 0);  // would make 3000 us
  EXPECT_EQ(events[3].flags & proto::kEventGuardHit, 0);  // after the dark one
}

// Fuzz finding (firmware/fuzz/crashes/guard-refused-then-same-us): a strobe
// edge the moment an exposure's all-off word lands is refused (the runs would
// join past the limit), and a second edge in that same microsecond found the
// last lit exposure forgotten by the refusal and the period 0 (no duty check):
// it lit the LEDs again, on for two exposures without a gap.
TEST(SequencingGuardSeam, ASecondTriggerInTheMicrosecondOfARefusedOneIsRefusedToo) {
  Rig rig;
  proto::SetGuardRequest guard = permissive_guard();
  guard.max_on_time_us.fill(10);
  ASSERT_EQ(rig.send(Command::kSetGuard, guard).status(), Status::kOk);
  arm_slave(rig, "1", 10);  // one slot of 10 us: exactly the limit
  rig.port.clear_led_transitions();
  rig.port.inject_strobe(1'000, 5);  // lit from 1000 to 1010
  rig.port.inject_strobe(1'010, 5);  // joins it: 20 us, refused
  rig.port.inject_strobe(1'010, 5);  // the same microsecond: still joins it, refused
  rig.port.inject_strobe(1'030, 5);  // after a gap: lit
  rig.port.run_until(2'000);
  EXPECT_LE(longest_on_us(rig.port.led_transitions(), 0), 10u);
  const auto events = rig.events();
  EXPECT_EQ(guard_hits(events), (std::vector<bool>{false, true, true, false}));
  EXPECT_EQ(rig.status().guard_hits, 2u);
}

TEST(Sequencing, GuardMeasuresTheDutyPeriodFromTheLastLitExposure) {
  Rig rig;
  proto::SetGuardRequest guard = permissive_guard();
  guard.max_duty_permille.fill(200);  // one 100 us slot: at least 500 us between exposures
  ASSERT_EQ(rig.send(Command::kSetGuard, guard).status(), Status::kOk);
  arm_slave(rig, "1", 100);
  rig.port.inject_strobe(1'000, 50);  // first: lit
  rig.port.inject_strobe(1'200, 50);  // 200 us after it: 50 %, refused
  rig.port.inject_strobe(1'200, 50);  // same microsecond: was period 0, unchecked; refused
  rig.port.inject_strobe(1'400, 50);  // 400 us after the lit one: 25 %, refused
  rig.port.inject_strobe(1'500, 50);  // 500 us after it: 20 %, lit (the refused ones lit nothing)
  rig.port.run_until(3'000);
  const auto events = rig.events();
  EXPECT_EQ(guard_hits(events), (std::vector<bool>{false, true, true, true, false}));
  const auto& log = rig.port.led_transitions();
  ASSERT_FALSE(log.empty());
  EXPECT_EQ(log.back().time_us, 1'600u);
}

}  // namespace
}  // namespace flutterscan::firmware::test
