// The datasheet's search, formula and line (docs/datasheet.md): the bisection
// finds a known threshold and backs off where labels fail now and then; the
// formula meets its physical limits; the line's session records and reads as
// the formula's camera says.

#include <gtest/gtest.h>

#include <cmath>

#include "bench/real_print_session.hpp"

#include "bench/envelope_formula.hpp"
#include "bench/envelope_setup.hpp"
#include "bench/line_labels.hpp"
#include "bench/speed_search.hpp"

namespace flutterscan::bench {
namespace {

TEST(SpeedSearch, FindsASharpThresholdAndVerifiesIt) {
  SpeedSearchOptions options;
  options.start = 0.7;
  const auto r = highest_reading_speed([](double v, std::uint64_t) { return v <= 2.0; }, options);
  EXPECT_TRUE(r.verified);
  EXPECT_EQ(r.final_labels, 300);
  EXPECT_LE(r.speed, 2.0);
  EXPECT_GE(r.speed, 2.0 / (1 + options.precision));
  EXPECT_EQ(r.back_offs, 0);
  EXPECT_FALSE(r.at_max);
}

TEST(SpeedSearch, BracketsDownwardFromATooHighStart) {
  SpeedSearchOptions options;
  options.start = 9;
  const auto r = highest_reading_speed([](double v, std::uint64_t) { return v <= 0.5; }, options);
  EXPECT_TRUE(r.verified);
  EXPECT_LE(r.speed, 0.5);
  EXPECT_GE(r.speed, 0.5 / (1 + options.precision));
}

TEST(SpeedSearch, BacksOffWhereOneLabelInFiftyFails) {
  // Above 1.8 m/s one label in 50 fails: 20 in a row often pass, 300 never do.
  SpeedSearchOptions options;
  options.start = 1;
  const auto reads = [](double v, std::uint64_t label) {
    if (v > 2.0) return false;
    return v <= 1.8 || label % 50 != 49;
  };
  const auto r = highest_reading_speed(reads, options);
  EXPECT_TRUE(r.verified);
  EXPECT_LE(r.speed, 1.8);
  EXPECT_GT(r.speed, 1.8 * options.back_off * options.back_off / (1 + options.precision));
}

TEST(SpeedSearch, ReportsNothingAndEverything) {
  SpeedSearchOptions options;
  const auto never = highest_reading_speed([](double, std::uint64_t) { return false; }, options);
  EXPECT_EQ(never.speed, 0);
  EXPECT_FALSE(never.verified);
  options.max_speed = 7;
  const auto always = highest_reading_speed([](double, std::uint64_t) { return true; }, options);
  EXPECT_TRUE(always.at_max);
  EXPECT_DOUBLE_EQ(always.speed, 7);
}

TEST(SpeedSearch, UsesEveryLabelNumberOnce) {
  std::vector<std::uint64_t> seen;
  SpeedSearchOptions options;
  options.final_labels = 30;
  highest_reading_speed(
      [&](double v, std::uint64_t label) {
        seen.push_back(label);
        return v <= 1.3;
      },
      options);
  for (std::size_t i = 0; i < seen.size(); ++i) EXPECT_EQ(seen[i], i);
}

TEST(EnvelopeSetup, UnitsOfTheLine) {
  const LineSetup line;  // 0.1 mm/px, 100 us slots, 52 slots
  EXPECT_NEAR(module_px(10, line), 2.54, 1e-12);
  EXPECT_NEAR(exposure_blur_px(1.0, line), 52, 1e-9);  // 1 m/s = 1 mm/ms: 5.2 mm
  EXPECT_NEAR(speed_for_motion(1, 0.1, line), 1.0, 1e-12);
  EXPECT_NEAR(exposure_electrons(100, line), 520, 1e-9);
  EXPECT_EQ(lit_run_slots(coded_scheme()), 1);
  EXPECT_EQ(lit_run_slots(strobe_scheme(4)), 4);
  EXPECT_TRUE(coded_scheme().one_of_three);
}

TEST(EnvelopeFormula, StrobeInBrightLightReachesTwoModulesPerPulse) {
  // Bright light (600 e-/ms): the pulse's motion may approach the box whose zero
  // is at the finest alternation, 2 modules, but not pass it.
  const LineSetup line;
  const double m = 3;
  const double limit = speed_for_motion(2 * m, line.slot_ms, line);  // 6 m/s
  const double v = formula_speed(
      [&](double s) { return line_capture(strobe_scheme(1), line, 600, s); }, m, 0.05, 50);
  EXPECT_LT(v, limit);
  EXPECT_GT(v, 0.75 * limit);
}

TEST(EnvelopeFormula, MoreLightAndBiggerModulesReadFaster) {
  const LineSetup line;
  const auto speed = [&](double light, double m) {
    return formula_speed([&](double s) { return line_capture(coded_scheme(), line, light, s); }, m,
                         0.05, 50);
  };
  EXPECT_LT(speed(30, 3), speed(600, 3));
  EXPECT_LT(speed(600, 2), speed(600, 4));
  EXPECT_EQ(normalized_sinc(0), 1);
  EXPECT_NEAR(normalized_sinc(0.5), 2 / M_PI, 1e-12);
}

TEST(EnvelopeFormula, ResolutionLimitPerDecoder) {
  EXPECT_EQ(lit_motion_modules(sim::SceneKind::kCode128), 1.0);
  EXPECT_EQ(lit_motion_modules(sim::SceneKind::kDataMatrix), 2.0);
  // 10 mil at 0.1 mm/px (2.54 px), one module in one 100 us slot: 2.54 m/s.
  EXPECT_NEAR(lit_motion_speed(1, 2.54, 0.1, 0.1), 2.54, 1e-12);
  EXPECT_NEAR(lit_motion_speed(2, 2.54, 0.1, 0.4), 1.27, 1e-12);
}

TEST(LineMotion, SlotsAddUpToTheBlurAndMoveForward) {
  const auto uniform = line_slot_boundaries(52, 104, 1, 0, 1);
  for (std::size_t t = 0; t < uniform.size(); ++t) EXPECT_NEAR(uniform[t], 2.0 * t, 1e-9);
  const auto b = line_slot_boundaries(52, 100, 1.05, 0.05, 7);
  ASSERT_EQ(b.size(), 53U);
  EXPECT_NEAR(b.back(), 100, 1e-9);
  for (std::size_t t = 1; t < b.size(); ++t) EXPECT_GE(b[t], b[t - 1]);
  // Faster at the end than at the start (on average over the first and last ten slots).
  EXPECT_GT(b[52] - b[42], b[10] - b[0]);
}

TEST(LinePath, TheSessionsCameraIsTheFormulasForCodedLightAndTheStrobe) {
  const LineSetup line;
  for (const auto& scheme : {coded_scheme(), strobe_scheme(2)}) {
    const auto path = line_path(scheme, line, 200, LineProcessing{});
    EXPECT_EQ(path.fps, 30);
    EXPECT_EQ(path.config.processing.workers, 2);
    const auto session = SessionLine(path.config, 400, 32, 52).model();
    const auto formula = line_capture(scheme, line, 200, 1.0);  // 1 m/s: 52 px
    EXPECT_TRUE(session.code == formula.code) << scheme.name;
    EXPECT_NEAR(session.blur_px, formula.blur_px, 1e-9);
    ASSERT_EQ(session.led_electrons.size(), 3U);
    for (std::size_t i = 0; i < 3; ++i)
      EXPECT_NEAR(session.led_electrons[i], formula.led_electrons[i], 1e-9) << scheme.name;
    EXPECT_EQ(session.crosstalk, formula.crosstalk);
    EXPECT_EQ(session.read_noise, formula.read_noise);
    EXPECT_EQ(session.full_well, formula.full_well);
    EXPECT_EQ(session.gain, formula.gain);
    EXPECT_EQ(session.black_level, formula.black_level);
    EXPECT_EQ(session.bit_depth, formula.bit_depth);
  }
  EXPECT_THROW(line_path(coded_scheme(), line, 200, {"sharpest", 30, 2}), std::invalid_argument);
}

TEST(LinePath, AStrobesLightFollowsItsPulseHoweverItIsCutIntoSlots) {
  const LineSetup line;  // 100 us slots
  const auto short_pulse = strobe_of_pulse(line, 25);
  EXPECT_NEAR(short_pulse.line.slot_ms, 0.025, 1e-12);
  EXPECT_EQ(lit_run_slots(short_pulse.scheme), 1);
  const auto long_pulse = strobe_of_pulse(line, 400);
  EXPECT_NEAR(long_pulse.line.slot_ms, 0.1, 1e-12);
  EXPECT_EQ(lit_run_slots(long_pulse.scheme), 4);
  const auto light = [&](double pulse_us) {
    const auto strobe = strobe_of_pulse(line, pulse_us);
    // electrons a lit slot gives, times the lit slots
    return line_capture(strobe.scheme, strobe.line, 200, 1.0).led_electrons[0] *
           lit_run_slots(strobe.scheme);
  };
  EXPECT_NEAR(light(25) / light(100), 0.25, 1e-9);
  EXPECT_NEAR(light(400) / light(100), 4, 1e-9);
  const auto coded = coded_of_slot(line, 50);
  EXPECT_NEAR(coded.line.slot_ms, 0.05, 1e-12);
  EXPECT_TRUE(coded.scheme.code == coded_scheme().code);
  // And the session runs each as the same white strobe.
  for (double pulse : kStrobePulsesUs) {
    const auto strobe = strobe_of_pulse(line, pulse);
    const auto path = line_path(strobe.scheme, strobe.line, 200, LineProcessing{});
    EXPECT_EQ(path.config.controller.slot_time_us, std::lround(strobe.line.slot_ms * 1000));
    EXPECT_TRUE(SessionLine(path.config, 400, 32, 20).model().code == strobe.scheme.code) << pulse;
  }
}

TEST(LabelLine, ALabelReadsThroughTheSessionWhereItsBlurCanBeUndoneAndNotWhereItCannot) {
  // 13-mil Code 128 (3.3 px modules) in bright light: at 0.5 m/s (26 px of
  // blur, a module per 7 slots) coded light and a one-slot strobe read it; at
  // 8 m/s a 4-slot strobe moves 32 px in its pulse, 10 modules, and nothing
  // undoes that.
  const LineSetup line;
  const auto labels = LabelLine::make(sim::SceneKind::kCode128, module_px(13, line), 2, 5);
  ASSERT_EQ(labels.error(), "");
  const LineMotion motion;
  int coded = 0, strobe = 0;
  for (std::uint64_t label = 0; label < 3; ++label) {
    const auto c = labels.read(line_path(coded_scheme(), line, 600, {"cascade", 0, 2}),
                               exposure_blur_px(0.5, line), motion, label);
    coded += c.read;
    EXPECT_GT(c.frame_ms, 0);
    strobe += labels
                  .read(line_path(strobe_scheme(1), line, 600, {"cascade", 0, 2}),
                        exposure_blur_px(0.5, line), motion, label)
                  .read;
  }
  EXPECT_EQ(coded, 3);
  EXPECT_EQ(strobe, 3);
  EXPECT_FALSE(labels
                   .read(line_path(strobe_scheme(4), line, 600, {"cascade", 0, 2}),
                         exposure_blur_px(8, line), motion, 0)
                   .read);
}

}  // namespace
}  // namespace flutterscan::bench
