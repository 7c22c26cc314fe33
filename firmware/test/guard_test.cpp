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

TEST(Guard, SeamJoinsThePreviousOnTimeToTheNextCodesLeadingRun) {
  std::array<std::uint64_t, kMaxLeds> previous{};
  previous[0] = 750;  // e.g. "0111" at 250 us slots
  // "1000" at 250 us: 1000 us at the seam.
  const GuardVerdict hit = check_led_guard_seam(previous, led_on_stats(code("1000", 1)), 250,
                                                limits(750, 1000));
  EXPECT_EQ(hit.status, GuardStatus::kOnTimeTooLong);
  EXPECT_EQ(hit.led, 0);
  EXPECT_EQ(hit.value, 1000u);
  EXPECT_EQ(hit.limit, 750u);
  // At a shorter slot time, or a code that starts dark, the seam fits.
  EXPECT_EQ(check_led_guard_seam(previous, led_on_stats(code("1000", 1)), 250, limits(1000, 1000))
                .status,
            GuardStatus::kOk);
  EXPECT_EQ(check_led_guard_seam(previous, led_on_stats(code("0100", 1)), 250, limits(750, 1000))
                .status,
            GuardStatus::kOk);
  // Per LED: LED 1 was off at the end, so its leading run alone counts.
  previous[1] = 0;
  GuardLimits per_led = limits(750, 1000);
  per_led.max_on_time_us[1] = 100;
  const GuardVerdict led1 =
      check_led_guard_seam(previous, led_on_stats(code("2200", 2)), 60, per_led);
  EXPECT_EQ(led1.status, GuardStatus::kOnTimeTooLong);
  EXPECT_EQ(led1.led, 1);
  EXPECT_EQ(led1.value, 120u);
}

}  // namespace
}  // namespace flutterscan
