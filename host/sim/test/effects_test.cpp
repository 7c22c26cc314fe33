// The forward model's extra effects (issue 7's stability study): speed varying
// within the exposure, colour objects, rolling-shutter readout; and the
// effects the plain model already has (ambient light, sRGB encoding).

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "codes/library.hpp"
#include "imaging/exposure_timeline.hpp"
#include "imaging/frame_conversion.hpp"
#include "sim/colour_scene.hpp"
#include "sim/forward_model.hpp"
#include "sim/speed_profile.hpp"
#include "sim/timeline_forward.hpp"

namespace flutterscan::sim {
namespace {

using imaging::CaptureModel;
using imaging::Plane;

CaptureModel triplet_capture(double blur = 52) {
  CaptureModel m;
  m.code = codes::to_code(*codes::find_library_code("found-mse"));
  m.blur_px = blur;
  m.crosstalk = {0.90, 0.08, 0.01, 0.10, 0.85, 0.12, 0.01, 0.07, 0.88};
  m.led_electrons = imaging::budgeted_led_electrons(m.code, 3000, 3);
  m.full_well = 1e9;
  return m;
}

Plane random_bars(int width, int height, unsigned seed) {
  Plane p(width, height, 0.35f);
  std::mt19937 rng(seed);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) p.at(x, y) = (rng() % 3 == 0) ? 0.06f : 0.9f;
  return p;
}

double max_abs_difference(const Plane& a, const Plane& b) {
  double worst = 0;
  for (std::size_t i = 0; i < a.pixels.size(); ++i)
    worst = std::max(worst, static_cast<double>(std::abs(a.pixels[i] - b.pixels[i])));
  return worst;
}

double sum_of(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return s;
}

TEST(ExposureTimeline, UniformSegmentsGiveChannelPsfTapForTap) {
  CaptureModel m = triplet_capture(37.3);  // a fractional slot width
  m.ambient_electrons = {50, 20, 10};
  const auto segments = imaging::slot_segments(m);
  for (int c = 0; c < 3; ++c) {
    const auto plain = imaging::channel_psf(m, c);
    const auto timed = imaging::timeline_channel_psf(m, c, segments);
    ASSERT_EQ(plain.size(), timed.size());
    for (std::size_t j = 0; j < plain.size(); ++j) EXPECT_NEAR(plain[j], timed[j], 1e-9) << j;
  }
}

TEST(ExposureTimeline, CyclicPhaseZeroIsUniformAndWholePhasesRotateTheCode) {
  const CaptureModel m = triplet_capture();
  for (int c = 0; c < 3; ++c) {
    const auto zero = imaging::timeline_channel_psf(m, c, imaging::cyclic_phase_segments(m, 0));
    const auto plain = imaging::channel_psf(m, c);
    ASSERT_EQ(zero.size(), plain.size());
    for (std::size_t j = 0; j < plain.size(); ++j) EXPECT_NEAR(zero[j], plain[j], 1e-9);
  }
  // Phase 5: the code rotated left by five slots.
  CaptureModel rotated = m;
  for (int t = 0; t < 52; ++t) rotated.code.set_mask(t, m.code.mask((t + 5) % 52));
  const auto shifted = imaging::timeline_channel_psf(m, 1, imaging::cyclic_phase_segments(m, 5));
  const auto expected = imaging::channel_psf(rotated, 1);
  ASSERT_EQ(shifted.size(), expected.size());
  for (std::size_t j = 0; j < expected.size(); ++j) EXPECT_NEAR(shifted[j], expected[j], 1e-9);
  // A fractional phase still collects exactly one cycle's light, and differs from both neighbours.
  const auto half = imaging::timeline_channel_psf(m, 1, imaging::cyclic_phase_segments(m, 4.5));
  EXPECT_NEAR(sum_of(half), sum_of(expected), 1e-9 * sum_of(expected));
  double change = 0;
  for (std::size_t j = 0; j < std::min(half.size(), expected.size()); ++j)
    change += std::abs(half[j] - expected[j]);
  EXPECT_GT(change, 0.05 * sum_of(expected));
}

TEST(SpeedProfile, ZeroJitterIsThePlainModelToFloatPrecision) {
  const CaptureModel m = triplet_capture(45.5);
  const Plane scene = random_bars(160, 12, 3);
  const auto boundaries = jittered_slot_boundaries(52, m.blur_px, 0.0, 9);
  const auto timed =
      expected_electrons_timeline(scene, m, imaging::segments_from_boundaries(m.code, boundaries));
  const auto plain = expected_electrons(scene, m);
  for (int c = 0; c < 3; ++c) {
    const auto& p = plain.channels[static_cast<std::size_t>(c)];
    double peak = 0;
    for (float v : p.pixels) peak = std::max(peak, static_cast<double>(v));
    EXPECT_LE(max_abs_difference(p, timed.channels[static_cast<std::size_t>(c)]), 1e-6 * peak);
  }
}

TEST(SpeedProfile, JitterAndAccelerationKeepTheBlurButMoveTheSlots) {
  const auto jitter = jittered_slot_boundaries(52, 52, 0.3, 4);
  EXPECT_DOUBLE_EQ(jitter.front(), 0.0);
  EXPECT_NEAR(jitter.back(), 52.0, 1e-9);
  double rms = 0;
  for (int t = 0; t < 52; ++t) {
    const double step =
        jitter[static_cast<std::size_t>(t) + 1] - jitter[static_cast<std::size_t>(t)];
    EXPECT_GE(step, 0.0);
    rms += (step - 1) * (step - 1);
  }
  rms = std::sqrt(rms / 52);
  EXPECT_GT(rms, 0.15);  // asked 0.3 of the nominal step: clearly not uniform
  EXPECT_LT(rms, 0.5);
  EXPECT_NE(jittered_slot_boundaries(52, 52, 0.3, 5), jitter);  // the seed matters

  const auto accel = accelerated_slot_boundaries(52, 52, 0.4);
  EXPECT_NEAR(accel.back(), 52.0, 1e-9);
  const double first = accel[1] - accel[0], last = accel[52] - accel[51];
  EXPECT_NEAR(first, 0.8 + 0.2 / 52, 1e-9);  // speed 0.8 v rising to 1.2 v (slot means)
  EXPECT_NEAR(last, 1.2 - 0.2 / 52, 1e-9);

  // The jittered frame differs from the plain one by much more than float rounding.
  const CaptureModel m = triplet_capture();
  const Plane scene = random_bars(160, 4, 8);
  const auto timed =
      expected_electrons_timeline(scene, m, imaging::segments_from_boundaries(m.code, jitter));
  const auto plain = expected_electrons(scene, m);
  EXPECT_GT(max_abs_difference(plain.channels[0], timed.channels[0]), 10.0);
}

TEST(RollingShutter, RowPhaseZeroIsTheGlobalModelAndRowsSeeTheirOwnPhase) {
  const CaptureModel m = triplet_capture();
  const Plane scene = random_bars(200, 6, 5);
  const auto global = expected_electrons(scene, m);
  // Line time 0: every row at phase 0, the global model.
  const auto none = expected_rolling_shutter_electrons(scene, m, 0.0, 19.0);
  ASSERT_TRUE(none.ok()) << none.error();
  for (int c = 0; c < 3; ++c)
    EXPECT_LE(max_abs_difference(global.channels[static_cast<std::size_t>(c)],
                                 none.value().channels[static_cast<std::size_t>(c)]),
              1e-3);
  // Line time 3 slots: row 0 is global, row 2 sees the code rotated by 6 slots.
  const auto rolling = expected_rolling_shutter_electrons(scene, m, 57.0, 19.0);
  ASSERT_TRUE(rolling.ok());
  CaptureModel rotated = m;
  for (int t = 0; t < 52; ++t) rotated.code.set_mask(t, m.code.mask((t + 6) % 52));
  const auto rotated_frame = expected_electrons(scene, rotated);
  for (int x = 0; x < 200; ++x) {
    EXPECT_NEAR(rolling.value().channels[1].at(x, 0), global.channels[1].at(x, 0), 1e-3);
    EXPECT_NEAR(rolling.value().channels[1].at(x, 2), rotated_frame.channels[1].at(x, 2), 1e-3);
  }
  double row2_change = 0;
  for (int x = 0; x < 200; ++x)
    row2_change += std::abs(rolling.value().channels[1].at(x, 2) - global.channels[1].at(x, 2));
  EXPECT_GT(row2_change, 1000.0);
  EXPECT_NEAR(rolling_shutter_phase(3, 30.0, 19.0, 52), 90.0 / 19.0, 1e-12);
  EXPECT_NEAR(rolling_shutter_phase(100, 30.0, 19.0, 52), std::fmod(3000.0 / 19.0, 52.0), 1e-9);
}

TEST(RollingShutter, RefusesMotionAlongYAndBadTimes) {
  CaptureModel m = triplet_capture();
  const Plane scene = random_bars(100, 100, 1);
  m.direction = imaging::Direction::kPlusY;
  EXPECT_FALSE(expected_rolling_shutter_electrons(scene, m, 10.0, 19.0).ok());
  m.direction = imaging::Direction::kPlusX;
  EXPECT_FALSE(expected_rolling_shutter_electrons(scene, m, 10.0, 0.0).ok());
  EXPECT_FALSE(expected_rolling_shutter_electrons(scene, m, -1.0, 19.0).ok());
}

TEST(ColourScene, EqualBandsAreTheGreyModelAndRedPrintVanishesInTheRedChannel) {
  CaptureModel m = triplet_capture();
  m.ambient_electrons = {40, 40, 40};
  const Plane scene = random_bars(160, 4, 2);
  const std::vector<Plane> grey_bands = {scene, scene, scene};
  const auto colour = expected_colour_electrons(grey_bands, m);
  ASSERT_TRUE(colour.ok()) << colour.error();
  const auto grey = expected_electrons(scene, m);
  for (int c = 0; c < 3; ++c)
    EXPECT_LE(max_abs_difference(grey.channels[static_cast<std::size_t>(c)],
                                 colour.value().channels[static_cast<std::size_t>(c)]),
              0.05);

  auto spec = parse_scene("code128:FS-0042").value();
  spec.width = 480;
  spec.height = 120;
  const auto red = render_colour_scene(spec, kRedInk);
  ASSERT_TRUE(red.ok()) << red.error();
  // Band contrast over the label: red band nearly paper, green band dark ink.
  const auto span = [](const Plane& p) {
    const auto [lo, hi] = std::minmax_element(p.pixels.begin(), p.pixels.end());
    return static_cast<double>(*hi - *lo);
  };
  const Plane& red_band = red.value()[0];
  EXPECT_NEAR(*std::min_element(red_band.pixels.begin(), red_band.pixels.end()), 0.35,
              1e-6);  // belt
  EXPECT_NEAR(*std::min_element(red.value()[1].pixels.begin(), red.value()[1].pixels.end()), 0.08,
              1e-6);
  EXPECT_GT(span(red.value()[1]), 0.8);
  const Plane fused = fuse_bands(red.value());
  EXPECT_NEAR(fused.at(0, 0), 0.35f, 1e-6);  // the belt is grey
  EXPECT_FALSE(render_colour_scene(spec, {0.5, 1.5, 0.1}).ok());
  std::vector<Plane> two = {red.value()[0], red.value()[1]};
  EXPECT_FALSE(expected_colour_electrons(two, m).ok());
}

TEST(ExistingEffects, AmbientLightAddsABoxAndSrgbRoundTrips) {
  CaptureModel m = triplet_capture();
  m.full_well = 12000;
  m.gain = 12000 / 4095.0;
  m.read_noise = 0;
  const Plane white(120, 4, 1.0f);
  const double dark_level = imaging::channel_white_electrons(m, 0);
  m.ambient_electrons = {500, 500, 500};
  EXPECT_NEAR(imaging::channel_white_electrons(m, 0), dark_level + 500, 1e-6);
  // sRGB-encoded DN linearised by the capture model give back the electrons (to quantisation).
  m.encoding = imaging::Encoding::kSrgb;
  const auto expected = expected_electrons(white, m);
  const auto frame = record_frame(expected, m, 1);
  const auto linear = imaging::dn_to_electrons(frame, m);
  const double truth = expected.channels[0].at(60, 2);
  EXPECT_NEAR(linear.channels[0].at(60, 2), truth, 0.05 * truth);
  CaptureModel as_linear = m;
  as_linear.encoding = imaging::Encoding::kLinear;  // the mistake the study measures
  EXPECT_GT(imaging::dn_to_electrons(frame, as_linear).channels[0].at(60, 2), 1.3 * truth);
}

}  // namespace
}  // namespace flutterscan::sim
