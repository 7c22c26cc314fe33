// The LEDs' compiled ceiling and the heat the guard never forgets: lit runs
// closer than the minimum off-time are one run, every boot starts the guard
// full, and no setting goes above BoardConfig::ceiling (issue 46, defects 1-3).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <vector>

#include "test_rig.hpp"

namespace flutterscan::firmware::test {
namespace {

using proto::Command;
using proto::Status;

/// LED `led`'s longest run in `log` with runs less than `min_off_us` apart
/// joined (the gap counted as on), as the LED's die sees it.
std::uint64_t longest_joined_run_us(const std::vector<sim::LedTransition>& log, int led,
                                    std::uint64_t min_off_us) {
  std::uint64_t longest = 0;
  bool on = false;
  bool have_run = false;
  std::uint64_t run_start = 0;
  std::uint64_t last_off = 0;
  for (const auto& w : log) {
    const bool now_on = ((w.led_mask >> led) & 1u) != 0;
    if (now_on && !on) {
      if (!have_run || w.time_us - last_off >= min_off_us) run_start = w.time_us;
      have_run = true;
    }
    if (!now_on && on) {
      last_off = w.time_us;
      longest = std::max(longest, last_off - run_start);
    }
    on = now_on;
  }
  return longest;
}

proto::SetGuardRequest guard(std::uint32_t on_us, std::uint16_t duty) {
  proto::SetGuardRequest r{};
  r.max_on_time_us.fill(on_us);
  r.max_duty_permille.fill(duty);
  return r;
}

// Defect 1: the next exposure starts after the end-of-table interrupt, so at
// least a microsecond after the last one ended, and runs were joined only when
// they touched: LED 0 lit 30-40 ms of one frame and 0-10 ms of the next, 50 us
// apart, a 20 ms pulse against a 10 ms limit every frame.
TEST(Ceiling, RunsAFewMicrosecondsApartAreOneRunForTheOnTimeLimit) {
  Rig rig(product_like_board());
  rig.port.run_until(1'000'000);  // the LEDs have cooled since boot
  ASSERT_EQ(rig.send(Command::kSetGuard, guard(10'000, 500)).status(), Status::kOk);
  ASSERT_EQ(rig.upload(0, "1001", 1), Status::kOk);
  ASSERT_EQ(rig.select(0), Status::kOk);
  ASSERT_EQ(rig.set_timing(10'000, 40'050), Status::kOk);
  ASSERT_EQ(rig.set_mode(proto::SyncMode::kFreeRun), Status::kOk);
  rig.port.clear_led_transitions();
  const Status armed = rig.arm();
  rig.port.run_for(20 * 40'050);
  ASSERT_EQ(rig.disarm(), Status::kOk);
  if (armed == Status::kOk) {
    EXPECT_GE(rig.port.led_transitions().size(), 4u);  // it did light
  }
  EXPECT_LE(longest_joined_run_us(rig.port.led_transitions(), 0, kLedMinOffTimeUs), 10'000u);
}

// Fuzz finding (firmware/fuzz/crashes/prearm-join-grows-with-a-later-start):
// the controller pre-arms a table the guard accepts for a start "now",
// assuming acceptance only grows with a later start. With joined runs it does
// not: a start later within the minimum off-time joins a longer gap. Frames
// 3050 us apart, LED 0 lit 0-2 ms of each 3 ms exposure: judged right after an
// exposure the join was 2 + 0 + 2 ms, but the frame came 1050 us later: 5050 us
// against a 5000 us limit.
TEST(Ceiling, APrearmedTableIsJudgedForTheLatestStartThatStillJoins) {
  Rig rig(product_like_board());
  rig.port.run_until(1'000'000);
  ASSERT_EQ(rig.send(Command::kSetGuard, guard(5'000, 500)).status(), Status::kOk);
  ASSERT_EQ(rig.upload(0, "100124", 3), Status::kOk);
  ASSERT_EQ(rig.select(0), Status::kOk);
  ASSERT_EQ(rig.set_timing(500, 3'050), Status::kOk);
  ASSERT_EQ(rig.set_mode(proto::SyncMode::kFreeRun), Status::kOk);
  rig.port.clear_led_transitions();
  ASSERT_EQ(rig.arm(), Status::kOk);
  for (int i = 0; i < 40; ++i) {
    rig.port.run_for(1'000);
    rig.controller().poll();  // the main loop re-decides the pre-arm
  }
  ASSERT_EQ(rig.disarm(), Status::kOk);
  EXPECT_GE(rig.port.led_transitions().size(), 4u);  // it did light
  EXPECT_LE(longest_joined_run_us(rig.port.led_transitions(), 0, kLedMinOffTimeUs), 5'000u);
}

// The library's one-of-3 codes at the default timing (100 us slots) still arm
// and play under the product's ceiling and default guard with the minimum
// off-time joining their runs.
TEST(Ceiling, OneOfThreeCodesAtTheDefaultTimingStillPlay) {
  Rig rig(product_like_board());
  rig.port.run_until(1'000'000);
  ASSERT_EQ(rig.upload(0, "2212441414112412441224111241244244242212442211444144", 3,
                       proto::kCodeFlagOneOfN),
            Status::kOk);
  ASSERT_EQ(rig.select(0), Status::kOk);
  ASSERT_EQ(rig.arm(), Status::kOk);
  rig.port.inject_strobe(1'100'000, 5'300);
  rig.port.inject_strobe(1'140'000, 5'300);  // 30 fps-like period
  rig.port.run_until(1'200'000);
  const auto events = rig.events();
  ASSERT_EQ(events.size(), 2u);
  for (const auto& e : events) EXPECT_EQ(e.flags & proto::kEventGuardHit, 0);
}

// Defect 2: a power-on (brown-out, pin) reset was taken for cold LEDs, so the
// first exposure after it had no duty check. The LEDs have their own supply.
TEST(Ceiling, APowerOnResetForgetsNoHeat) {
  Rig rig(product_like_board());
  ASSERT_EQ(rig.send(Command::kSetGuard, guard(256'000, 100)).status(),
            Status::kAboveCeiling);  // 256 ms is above the 100 ms ceiling
  ASSERT_EQ(rig.send(Command::kSetGuard, guard(100'000, 100)).status(), Status::kOk);
  // 52 slots at 1 ms, LED 0 lit in 40 of them in runs of 10 ms: 77 % of the exposure.
  ASSERT_EQ(rig.upload(0, "1111111111011111111110111111111101111111111000000000", 1), Status::kOk);
  ASSERT_EQ(rig.select(0), Status::kOk);
  ASSERT_EQ(rig.set_timing(1'000), Status::kOk);
  ASSERT_EQ(rig.send(Command::kSaveConfig).status(), Status::kOk);
  for (int cycle = 0; cycle < 5; ++cycle) {
    // The host cycles the USB port: the MCU powers up again, the LEDs stay powered.
    rig.port.set_reset_cause(ResetCause::kPowerOn);
    rig.reboot();
    const std::uint64_t boot = rig.port.now_us();
    rig.port.clear_led_transitions();
    ASSERT_EQ(rig.arm(), Status::kOk);
    rig.port.inject_strobe(boot + 10'000, 60'000);
    rig.port.run_for(100'000);
    const std::uint64_t end = rig.port.now_us();
    // 10 % of the time since boot, plus nothing: the exposure at 10 ms needs 400 ms.
    EXPECT_LE(on_time_us(rig.port.led_transitions(), 0, boot, end) * 1000, 100u * (end - boot))
        << "cycle " << cycle;
  }
}

// Defect 3: SetGuard took anything up to the protocol's limits.
TEST(Ceiling, SetGuardAboveTheCeilingIsRefusedAndChangesNothing) {
  Rig rig(product_like_board());
  const auto before = rig.settings_snapshot();
  proto::SetGuardRequest on_time = guard(100'000, 500);
  on_time.max_on_time_us[2] = 100'001;
  EXPECT_EQ(rig.send(Command::kSetGuard, on_time).status(), Status::kAboveCeiling);
  proto::SetGuardRequest duty = guard(100'000, 500);
  duty.max_duty_permille[1] = 501;
  EXPECT_EQ(rig.send(Command::kSetGuard, duty).status(), Status::kAboveCeiling);
  EXPECT_EQ(rig.settings_snapshot(), before);
  EXPECT_EQ(rig.send(Command::kSetGuard, guard(50'000, 200)).status(), Status::kOk);
  EXPECT_STREQ(proto::status_text(Status::kAboveCeiling),
               "above the LED ceiling compiled into the firmware");
}

// Defect 3: a configuration saved by an image with a higher (or no) ceiling is
// tightened to this image's ceiling when loaded, never used above it.
TEST(Ceiling, ASavedConfigurationAboveTheCeilingIsTightenedWhenLoaded) {
  Rig rig;  // the protocol's ceiling: 2.56 s, 100 %
  ASSERT_EQ(rig.send(Command::kSetGuard, guard(proto::kMaxGuardOnTimeUs, 1000)).status(),
            Status::kOk);
  ASSERT_EQ(rig.send(Command::kSaveConfig).status(), Status::kOk);
  Rig product(product_like_board(), false);
  std::copy(rig.port.flash_page().begin(), rig.port.flash_page().end(),
            product.port.flash_page().begin());
  product.reboot();
  const GuardLimits& loaded = product.controller().settings().guard;
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(loaded.max_on_time_us[static_cast<std::size_t>(k)], 100'000u);
    EXPECT_EQ(loaded.max_duty_permille[static_cast<std::size_t>(k)], 500u);
  }
}

// Fuzz finding (crashes/default-brightness-above-the-ceiling): the factory
// settings had full brightness whatever the ceiling's current.
TEST(Ceiling, FactorySettingsAreWithinTheCeiling) {
  BoardConfig board = product_like_board();
  board.ceiling.max_current_permille = {700, 600, 500, 400};
  board.ceiling.max_duty_permille = {300, 300, 300, 300};
  Rig rig(board);
  const ControllerSettings& s = rig.controller().settings();
  EXPECT_EQ(s.brightness_permille, (std::array<std::uint16_t, kMaxLeds>{700, 600, 500, 400}));
  EXPECT_EQ(s.guard.max_duty_permille[0], 300u);
  EXPECT_EQ(rig.port.led_brightness(0), 700u);
}

// Defect 3: brightness above the ceiling's current is refused; the duty cap
// is energy, so Arm judges the code at the current brightness, and the current
// cannot rise while a code is armed (the guard judged its tables at the old one).
TEST(Ceiling, BrightnessCountsAsEnergyAndCannotExceedTheCeilingCurrent) {
  BoardConfig board = product_like_board();
  board.ceiling.max_current_permille = {700, 700, 700, 700};
  Rig rig(board);
  rig.port.run_until(1'000'000);
  proto::SetBrightnessRequest bright{};
  bright.permille = {701, 500, 500, 0};
  EXPECT_EQ(rig.send(Command::kSetBrightness, bright).status(), Status::kAboveCeiling);
  bright.permille = {350, 350, 350, 0};
  ASSERT_EQ(rig.send(Command::kSetBrightness, bright).status(), Status::kOk);
  // 50 % energy duty: "1" at 1 ms lit every 1.5 ms is 67 % of the time, at half
  // current 33 % of full-current energy: within the cap; at 700 per mille 47 %.
  ASSERT_EQ(rig.send(Command::kSetGuard, guard(100'000, 350)).status(), Status::kOk);
  ASSERT_EQ(rig.upload(0, "1", 1), Status::kOk);
  ASSERT_EQ(rig.select(0), Status::kOk);
  ASSERT_EQ(rig.set_timing(1'000, 4'000), Status::kOk);
  ASSERT_EQ(rig.set_mode(proto::SyncMode::kFreeRun), Status::kOk);
  ASSERT_EQ(rig.arm(), Status::kOk);
  rig.port.run_for(41'500);              // between two exposures
  bright.permille = {700, 350, 350, 0};  // more current while armed: refused
  EXPECT_EQ(rig.send(Command::kSetBrightness, bright).status(), Status::kBadState);
  EXPECT_EQ(rig.port.led_brightness(0), 350u);
  bright.permille = {300, 350, 350, 0};  // less: always
  EXPECT_EQ(rig.send(Command::kSetBrightness, bright).status(), Status::kOk);
  EXPECT_EQ(rig.port.led_brightness(0), 300u);
  ASSERT_EQ(rig.disarm(), Status::kOk);
  // 1 ms lit every 1.5 ms: 67 % of the time; 233 per mille of energy at 350,
  // 467 at 700 (the guard's cap is 350).
  ASSERT_EQ(rig.set_timing(1'000, 1'500), Status::kOk);
  bright.permille = {700, 350, 350, 0};
  ASSERT_EQ(rig.send(Command::kSetBrightness, bright).status(), Status::kOk);
  EXPECT_EQ(rig.arm(), Status::kGuardLimit);
  bright.permille = {350, 350, 350, 0};
  ASSERT_EQ(rig.send(Command::kSetBrightness, bright).status(), Status::kOk);
  EXPECT_EQ(rig.arm(), Status::kOk);
}

}  // namespace
}  // namespace flutterscan::firmware::test
