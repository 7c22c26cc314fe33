#include <gtest/gtest.h>

#include "flutterscan/common/sequencer.hpp"

namespace flutterscan {
namespace {

LedCode code(std::string_view digits, int leds) {
  return LedCode::parse(digits, leds).value();
}

GuardLimits limits(std::uint32_t on_us, std::uint16_t duty) {
  GuardLimits l;
  l.max_on_time_us.fill(on_us);
  l.max_duty_permille.fill(duty);
  return l;
}

TEST(LedOnStats, CountsRunsWithinAndAcrossExposures) {
  const LedOnStats stats = led_on_stats(code("1101110011", 1));
  EXPECT_EQ(stats.on_slots[0], 7);
  EXPECT_EQ(stats.longest_run_slots[0], 3);
  EXPECT_EQ(stats.longest_cyclic_run_slots[0], 4);  // trailing 11 + leading 11

  const LedOnStats triplet = led_on_stats(code("112441", 3));
  EXPECT_EQ(triplet.on_slots[0], 3);
  EXPECT_EQ(triplet.longest_run_slots[0], 2);
  EXPECT_EQ(triplet.longest_cyclic_run_slots[0], 3);
  EXPECT_EQ(triplet.longest_run_slots[2], 2);
  EXPECT_EQ(triplet.on_slots[1], 1);
}

TEST(LedOnStats, AnLedOnInEverySlotNeverTurnsOffBackToBack) {
  const LedOnStats stats = led_on_stats(code("1111", 1));
  EXPECT_EQ(stats.longest_run_slots[0], 4);
  EXPECT_EQ(stats.longest_cyclic_run_slots[0], 4);
}

TEST(Guard, PassesWithinLimits) {
  const LedOnStats stats = led_on_stats(code("112441", 3));
  const GuardVerdict verdict = check_led_guard(stats, 100, 1000, limits(200, 500));
  EXPECT_EQ(verdict.status, GuardStatus::kOk);
  EXPECT_EQ(verdict.led, -1);
}

TEST(Guard, TripsOnContinuousOnTimeAndNamesTheLed) {
  const LedOnStats stats = led_on_stats(code("121444", 3));
  const GuardVerdict verdict = check_led_guard(stats, 100, 0, limits(200, 1000));
  EXPECT_EQ(verdict.status, GuardStatus::kOnTimeTooLong);
  EXPECT_EQ(verdict.led, 2);
  EXPECT_EQ(verdict.value, 300u);
  EXPECT_EQ(verdict.limit, 200u);
  EXPECT_EQ(check_led_guard(stats, 66, 0, limits(200, 1000)).status, GuardStatus::kOk);
}

TEST(Guard, PerLedLimits) {
  const LedOnStats stats = led_on_stats(code("1124", 3));
  GuardLimits l = limits(1000, 1000);
  l.max_on_time_us[1] = 50;
  const GuardVerdict verdict = check_led_guard(stats, 100, 0, l);
  EXPECT_EQ(verdict.status, GuardStatus::kOnTimeTooLong);
  EXPECT_EQ(verdict.led, 1);
}

TEST(Guard, DutyIsOnTimeOverThePeriodRoundedUp) {
  // LED 0: 3 of 6 slots at 100 us = 300 us per exposure.
  const LedOnStats stats = led_on_stats(code("112441", 3));
  EXPECT_EQ(check_led_guard(stats, 100, 1000, limits(10'000, 300)).status, GuardStatus::kOk);
  const GuardVerdict verdict = check_led_guard(stats, 100, 999, limits(10'000, 300));
  EXPECT_EQ(verdict.status, GuardStatus::kDutyTooHigh);
  EXPECT_EQ(verdict.led, 0);
  EXPECT_EQ(verdict.value, 301u);
  // Unknown period: no duty check.
  EXPECT_EQ(check_led_guard(stats, 100, 0, limits(10'000, 1)).status, GuardStatus::kOk);
}

TEST(Guard, BackToBackExposuresJoinRunsAndUseTheExposureAsPeriod) {
  const LedOnStats stats = led_on_stats(code("1101110011", 1));
  // Exposure 1000 us; separate exposures: longest run 300 us.
  EXPECT_EQ(check_led_guard(stats, 100, 2000, limits(300, 1000)).status, GuardStatus::kOk);
  // Back to back: the trailing and leading runs join to 400 us.
  EXPECT_EQ(check_led_guard(stats, 100, 1000, limits(300, 1000)).status,
            GuardStatus::kOnTimeTooLong);
  EXPECT_EQ(check_led_guard(stats, 100, 1000, limits(400, 700)).status, GuardStatus::kOk);
  EXPECT_EQ(check_led_guard(stats, 100, 1000, limits(400, 699)).status, GuardStatus::kDutyTooHigh);
}

}  // namespace
}  // namespace flutterscan
