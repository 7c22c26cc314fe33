#include <gtest/gtest.h>

#include "flutterscan/common/joined_runs.hpp"
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

TEST(LedOnStats, KeepsLeadingAndTrailingRunsApart) {
  const LedOnStats stats = led_on_stats(code("110111", 1));
  EXPECT_EQ(stats.leading_run_slots[0], 2);
  EXPECT_EQ(stats.trailing_run_slots[0], 3);
  const LedOnStats mixed = led_on_stats(code("1244", 3));  // LED 0 first, LED 2 last, LED 1 middle
  EXPECT_EQ(mixed.leading_run_slots[0], 1);
  EXPECT_EQ(mixed.trailing_run_slots[0], 0);
  EXPECT_EQ(mixed.leading_run_slots[1], 0);
  EXPECT_EQ(mixed.trailing_run_slots[1], 0);
  EXPECT_EQ(mixed.leading_run_slots[2], 0);
  EXPECT_EQ(mixed.trailing_run_slots[2], 2);
  const LedOnStats all_on = led_on_stats(code("1111", 1));
  EXPECT_EQ(all_on.leading_run_slots[0], 4);
  EXPECT_EQ(all_on.trailing_run_slots[0], 4);
}

TEST(JoinedRuns, RunsCloserThanTheMinimumOffTimeAreOneRunWithTheGapCountedAsOn) {
  // "1101110011" at 100 us: runs 0-200, 300-600, 800-1000 us; gaps 100 and 200 us.
  const LedCode c = code("1101110011", 1);
  const JoinedRuns apart = joined_runs(c, 0, 100, 101);  // only the 200 us gap separates
  EXPECT_TRUE(apart.lit);
  EXPECT_EQ(apart.first_on_us, 0u);
  EXPECT_EQ(apart.first_run_us, 600u);  // 0-600: the 100 us gap joined
  EXPECT_EQ(apart.last_off_us, 1000u);
  EXPECT_EQ(apart.last_run_us, 200u);
  EXPECT_EQ(apart.longest_us, 600u);
  EXPECT_FALSE(apart.one_run());
  const JoinedRuns joined = joined_runs(c, 0, 100, 201);  // every gap joins
  EXPECT_EQ(joined.longest_us, 1000u);
  EXPECT_TRUE(joined.one_run());
  const JoinedRuns exact = joined_runs(c, 0, 100, 1);  // no gap is shorter than 1 us
  EXPECT_EQ(exact.longest_us, 300u);
  EXPECT_EQ(exact.first_run_us, 200u);
  // An LED the code does not light, or one beyond its LED count.
  EXPECT_FALSE(joined_runs(code("2200", 2), 0, 100, 100).lit);
  EXPECT_FALSE(joined_runs(c, 1, 100, 100).lit);
}

}  // namespace
}  // namespace flutterscan
