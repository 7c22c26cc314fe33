// The forward model, and deblurring its frames: the simulator and every
// method share channel_psf, so a frame simulated here is the exact problem
// each method claims to solve.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "imaging/capture_descriptor.hpp"
#include "imaging/deblur.hpp"
#include "imaging/frame_conversion.hpp"
#include "imaging/joint_wiener.hpp"
#include "imaging/metrics.hpp"
#include "imaging/motion_frame.hpp"
#include "sim/forward_model.hpp"

namespace flutterscan::sim {
namespace {

using imaging::CaptureModel;
using imaging::Direction;
using imaging::Plane;

/// A label-like scene: random bars along x (2-6 px wide, ink 0.06 or paper 0.9), on belt grey rows.
Plane bars(int width, int height, unsigned seed) {
  Plane p(width, height, 0.35f);
  std::mt19937 rng(seed);
  std::vector<float> pattern(static_cast<std::size_t>(width));
  for (int x = 0; x < width;) {
    const int run = 2 + static_cast<int>(rng() % 5);
    const float value = (rng() % 2) ? 0.9f : 0.06f;
    for (int i = 0; i < run && x < width; ++i, ++x) pattern[static_cast<std::size_t>(x)] = value;
  }
  for (int y = height / 8; y < height - height / 8; ++y)
    for (int x = 0; x < width; ++x) p.at(x, y) = pattern[static_cast<std::size_t>(x)];
  return p;
}

CaptureModel coded_capture(double electrons, double blur) {
  CaptureModel m;
  m.code = LedCode::parse("2212441414112412441224111241244244242212442211444144", 3).value();
  m.blur_px = blur;
  m.led_electrons = imaging::budgeted_led_electrons(m.code, electrons, 3);
  m.read_noise = 4;
  m.full_well = 1e9;  // no saturation unless a test asks for it
  m.bit_depth = 16;
  m.gain = 1;
  return m;
}

imaging::Image simulate(const Plane& scene, const CaptureModel& m, std::uint64_t seed) {
  return imaging::dn_to_electrons(record_frame(expected_electrons(scene, m), m, seed), m);
}

double deblurred_psnr(const Plane& scene, const CaptureModel& m, imaging::DeblurOptions options,
                      std::uint64_t seed = 1) {
  const auto result = imaging::deblur(simulate(scene, m, seed), m, options);
  EXPECT_TRUE(result.ok()) << (result.ok() ? "" : result.error());
  const auto region = imaging::scored_region(scene.width, scene.height, m.blur_px, m.direction);
  return imaging::psnr(scene, result.value().latent, region);
}

TEST(ForwardModel, WhiteSceneGivesTheChannelWhiteLevel) {
  const CaptureModel m = coded_capture(3000, 52);
  const auto e = expected_electrons(Plane(200, 10, 1.0f), m);
  for (int c = 0; c < 3; ++c)
    EXPECT_NEAR(e.channels[static_cast<std::size_t>(c)].at(100, 5),
                imaging::channel_white_electrons(m, c), 1e-3);
}

TEST(ForwardModel, ShotAndReadNoiseHaveTheirVariance) {
  CaptureModel m = coded_capture(3000, 0);
  const auto frame = simulate(Plane(256, 256, 0.5f), m, 7);
  const Plane& red = frame.channels[0];
  double mean = 0, square = 0;
  for (float v : red.pixels) mean += v;
  mean /= static_cast<double>(red.pixels.size());
  for (float v : red.pixels) square += (v - mean) * (v - mean);
  const double variance = square / static_cast<double>(red.pixels.size() - 1);
  const double expected_mean = 0.5 * imaging::channel_white_electrons(m, 0);
  EXPECT_NEAR(mean, expected_mean, 0.01 * expected_mean);
  EXPECT_NEAR(variance, expected_mean + 16 + 1.0 / 12, 0.05 * expected_mean);
}

TEST(ForwardModel, SameSeedSameFrameOtherSeedOtherNoise) {
  const CaptureModel m = coded_capture(1000, 20);
  const Plane scene = bars(128, 16, 1);
  const auto e = expected_electrons(scene, m);
  EXPECT_EQ(record_frame(e, m, 3).channels[1].pixels, record_frame(e, m, 3).channels[1].pixels);
  EXPECT_NE(record_frame(e, m, 3).channels[1].pixels, record_frame(e, m, 4).channels[1].pixels);
}

TEST(ForwardModel, SaturatesAtFullWellAndQuantises) {
  CaptureModel m = coded_capture(3000, 0);
  m.full_well = 500;
  m.gain = 2;
  m.bit_depth = 8;
  m.black_level = 10;
  const auto frame = record_frame(expected_electrons(Plane(32, 32, 1.0f), m), m, 1);
  for (float v : frame.channels[0].pixels) {
    EXPECT_LE(v, 255.0f);
    EXPECT_EQ(v, std::round(v));
  }
  // 500 e- / 2 + 10 = 260 DN, clipped to 255.
  EXPECT_EQ(frame.channels[0].at(5, 5), 255.0f);
}

TEST(ForwardModel, BayerMosaicTakesEachSiteFromItsChannel) {
  CaptureModel m = coded_capture(3000, 0);
  m.read_noise = 0;
  m.bayer_rggb = true;
  imaging::Image expected;
  for (float level : {100.0f, 200.0f, 300.0f}) expected.channels.push_back(Plane(4, 4, level));
  m.ambient_electrons = {0, 0, 0};
  const auto mosaic = record_frame(expected, m, 1);
  ASSERT_EQ(mosaic.channel_count(), 1);
  // Poisson noise around each channel's level: R at (0,0), G at (1,0) and (0,1), B at (1,1).
  EXPECT_NEAR(mosaic.channels[0].at(0, 0), 100, 50);
  EXPECT_NEAR(mosaic.channels[0].at(1, 0), 200, 60);
  EXPECT_NEAR(mosaic.channels[0].at(1, 1), 300, 70);
}

TEST(Deblur, JointWienerRecoversACodedBlur) {
  const Plane scene = bars(512, 64, 2);
  const CaptureModel m = coded_capture(3000, 52);
  const double restored = deblurred_psnr(scene, m, {});
  // The blurred frame itself, scaled to reflectance, scores far lower.
  const auto frame = simulate(scene, m, 1);
  Plane blurred(scene.width, scene.height);
  double white = 0;
  for (int c = 0; c < 3; ++c) white += imaging::channel_white_electrons(m, c);
  for (std::size_t i = 0; i < blurred.pixels.size(); ++i)
    blurred.pixels[i] = static_cast<float>(
        (frame.channels[0].pixels[i] + frame.channels[1].pixels[i] + frame.channels[2].pixels[i]) /
        white);
  const auto region = imaging::scored_region(scene.width, scene.height, 52, Direction::kPlusX);
  EXPECT_GT(restored, 20.0);
  EXPECT_GT(restored, imaging::psnr(scene, blurred, region) + 8.0);
}

TEST(Deblur, EveryDirectionGivesTheSameQuality) {
  const Plane along_x = bars(384, 48, 3);
  CaptureModel m = coded_capture(3000, 40);
  const double reference = deblurred_psnr(along_x, m, {});
  for (Direction d : {Direction::kMinusX, Direction::kPlusY, Direction::kMinusY}) {
    m.direction = d;
    const Plane scene = imaging::from_motion_frame(along_x, d);
    EXPECT_NEAR(deblurred_psnr(scene, m, {}), reference, 0.5) << imaging::direction_name(d);
  }
}

TEST(Deblur, JointBeatsPerChannelAveraging) {
  const Plane scene = bars(512, 64, 4);
  CaptureModel m = coded_capture(1000, 52);
  m.crosstalk = {0.90, 0.08, 0.01, 0.10, 0.85, 0.12, 0.01, 0.07, 0.88};
  imaging::DeblurOptions average;
  average.method = imaging::Method::kWienerAverage;
  EXPECT_GT(deblurred_psnr(scene, m, {}), deblurred_psnr(scene, m, average) + 1.0);
}

TEST(Deblur, RichardsonLucyConvergesTowardTheScene) {
  const Plane scene = bars(384, 32, 5);
  const CaptureModel m = coded_capture(3000, 52);
  imaging::DeblurOptions one;
  one.method = imaging::Method::kRichardsonLucy;
  one.iterations = 1;
  imaging::DeblurOptions twenty = one;
  twenty.iterations = 20;
  const double after_one = deblurred_psnr(scene, m, one);
  const double after_twenty = deblurred_psnr(scene, m, twenty);
  EXPECT_GT(after_twenty, after_one + 3.0);
  EXPECT_GT(after_twenty, 17.0);
}

// Joint Wiener transforms rows two at a time (one complex row): each row comes
// out as it does alone, whatever row it is paired with, an odd last row too.
TEST(Deblur, JointWienerGivesARowTheSameLatentAloneAndInAPair) {
  const Plane scene = bars(384, 3, 7);
  const CaptureModel m = coded_capture(1000, 52);
  const imaging::Image frame = simulate(scene, m, 5);
  std::vector<imaging::ChannelPsf> psfs;
  for (int c = 0; c < 3; ++c) psfs.push_back({imaging::channel_psf(m, c), 400.0});
  imaging::JointWiener wiener(psfs, scene.width, 1.0 / imaging::kLabelGradientVariance);
  const Plane together = wiener.deconvolve(frame.channels, 1);
  for (int y = 0; y < 3; ++y) {
    std::vector<Plane> one_row;
    for (const Plane& channel : frame.channels) {
      Plane row = Plane::uninitialised(channel.width, 1);
      std::copy(channel.row(y).begin(), channel.row(y).end(), row.row(0).begin());
      one_row.push_back(std::move(row));
    }
    const Plane alone = wiener.deconvolve(one_row, 1);
    const auto a = together.row(y), b = alone.row(0);
    float largest = 0, spread = 0;
    for (std::size_t x = 0; x < a.size(); ++x) {
      largest = std::max(largest, std::abs(a[x] - b[x]));
      spread = std::max(spread, std::abs(a[x] - a[0]));
    }
    EXPECT_LT(largest, 1e-5f) << "row " << y;
    EXPECT_GT(spread, 0.3f) << "row " << y;  // the row has print on it
  }
}

// The session's flat rows: belt rows are filled with the latent of a constant
// row, and every row with print on it (bars, or just a label's edges) is
// deconvolved as without the option (to float rounding: rows are transformed
// in pairs, and which rows pair up depends on the rows filled).
TEST(Deblur, FlatRowsAreFilledAndRowsWithPrintAreNot) {
  for (const double electrons : {300.0, 3000.0}) {
    SCOPED_TRACE(electrons);
    Plane scene = bars(640, 96, 5);  // belt rows 0-11 and 84-95, bars between
    // Rows 2-4: a label's paper edge to edge (0.9 from x = 200 to 440), no print.
    for (int y = 2; y < 5; ++y)
      for (int x = 200; x < 440; ++x) scene.at(x, y) = 0.9f;
    const CaptureModel m = coded_capture(electrons, 52);
    const imaging::Image frame = simulate(scene, m, 11);
    imaging::DeblurOptions every_row;
    imaging::DeblurOptions skipping = every_row;
    skipping.skip_flat_rows = true;
    const auto full = imaging::deblur(frame, m, every_row);
    const auto skipped = imaging::deblur(frame, m, skipping);
    ASSERT_TRUE(full.ok() && skipped.ok());
    EXPECT_EQ(full.value().flat_rows, 0);
    EXPECT_EQ(skipped.value().flat_rows, 24 - 3);  // the belt rows, not the paper's
    for (int y = 0; y < scene.height; ++y) {
      const auto a = full.value().latent.row(y), b = skipped.value().latent.row(y);
      const bool belt = (y < 12 || y >= 84) && !(y >= 2 && y < 5);
      if (!belt) {
        float largest = 0;
        for (std::size_t x = 0; x < a.size(); ++x)
          largest = std::max(largest, std::abs(a[x] - b[x]));
        EXPECT_LT(largest, 1e-5f) << "row " << y;
        continue;
      }
      // A constant: the deconvolved row's mean, and the belt's reflectance.
      double mean = 0;
      for (float v : a) mean += v;
      mean /= static_cast<double>(a.size());
      EXPECT_EQ(*std::min_element(b.begin(), b.end()), *std::max_element(b.begin(), b.end()))
          << "row " << y;
      EXPECT_NEAR(b[0], mean, 0.01) << "row " << y;
      EXPECT_NEAR(b[0], 0.35, 0.02) << "row " << y;
    }
  }
}

// Noise alone, at a level of its own per row: every row is flat; rows that
// carry a small code (100 px of 1-px bars, 25% and 75% reflectance) at 300 e-,
// or a ramp of 5% along them at 3000 e-, are not.
TEST(Deblur, FlatRowsFollowTheNoiseOfTheirLevel) {
  const CaptureModel m = coded_capture(3000, 52);
  Plane ramp(512, 40);
  for (int y = 0; y < ramp.height; ++y)
    for (int x = 0; x < ramp.width; ++x) ramp.at(x, y) = 0.05f + 0.9f * y / ramp.height;
  imaging::DeblurOptions skipping;
  skipping.skip_flat_rows = true;
  const auto flat = imaging::deblur(simulate(ramp, m, 3), m, skipping);
  ASSERT_TRUE(flat.ok());
  EXPECT_EQ(flat.value().flat_rows, ramp.height);
  Plane small_code(1920, 40, 0.5f);
  std::mt19937 rng(4);
  for (int x = 900; x < 1000; ++x) {
    const float v = rng() % 2 ? 0.75f : 0.25f;
    for (int y = 0; y < small_code.height; ++y) small_code.at(x, y) = v;
  }
  const CaptureModel dim = coded_capture(300, 52);
  const auto code = imaging::deblur(simulate(small_code, dim, 3), dim, skipping);
  ASSERT_TRUE(code.ok());
  EXPECT_EQ(code.value().flat_rows, 0);
  Plane shaded(1920, 40);
  for (int y = 0; y < shaded.height; ++y)
    for (int x = 0; x < shaded.width; ++x) shaded.at(x, y) = 0.5f * (1 + 0.05f * x / 1920);
  const auto shading = imaging::deblur(simulate(shaded, m, 3), m, skipping);
  ASSERT_TRUE(shading.ok());
  EXPECT_EQ(shading.value().flat_rows, 0);
}

// The flat-row test judges a row from its levels (imaging/row_levels.hpp): the
// motion frame's, made while converting, give the latent the rows themselves
// give, bit for bit; levels that say otherwise are what the test reads.
TEST(Deblur, FlatRowsAreJudgedFromTheRowLevelsGiven) {
  Plane scene = bars(640, 96, 5);  // belt rows 0-11 and 84-95, bars between
  const CaptureModel m = coded_capture(1000, 52);
  const imaging::Image frame = simulate(scene, m, 11);
  std::vector<imaging::ChannelPsf> psfs;
  for (int c = 0; c < 3; ++c) psfs.push_back({imaging::channel_psf(m, c), 400.0});
  imaging::JointWiener wiener(psfs, scene.width, 1.0 / imaging::kLabelGradientVariance);
  wiener.skip_flat_rows(std::vector<double>(3, imaging::channel_noise_variance(m, 0)));
  const Plane from_rows = wiener.deconvolve(frame.channels, 1);
  const int flat = wiener.flat_rows();
  EXPECT_EQ(flat, 24);
  const imaging::RowLevels levels = imaging::RowLevels::of(frame);
  const Plane from_levels = wiener.deconvolve(frame.channels, 2, &levels);
  EXPECT_EQ(wiener.flat_rows(), flat);
  EXPECT_EQ(from_levels.pixels, from_rows.pixels);
  // Levels that call every row flat at 100 e-: every row is filled with their constant.
  imaging::RowLevels flat_levels(3, scene.height, scene.width);
  for (int c = 0; c < 3; ++c)
    for (int y = 0; y < scene.height; ++y)
      flat_levels.set(c, y, {100.0f * static_cast<float>(scene.width), 0.0});
  const Plane told_flat = wiener.deconvolve(frame.channels, 1, &flat_levels);
  EXPECT_EQ(wiener.flat_rows(), scene.height);
  EXPECT_EQ(*std::min_element(told_flat.pixels.begin(), told_flat.pixels.end()),
            *std::max_element(told_flat.pixels.begin(), told_flat.pixels.end()));
  // Levels of another size are not used.
  const imaging::RowLevels other(3, scene.height - 1, scene.width);
  const Plane ignored = wiener.deconvolve(frame.channels, 1, &other);
  EXPECT_EQ(ignored.pixels, from_rows.pixels);
}

TEST(Deblur, RefusesBlurLongerThanTheImageAndChannelMismatch) {
  const CaptureModel m = coded_capture(3000, 52);
  imaging::Image small;
  for (int c = 0; c < 3; ++c) small.channels.push_back(Plane(40, 8));
  const auto refused = imaging::deblur(small, m, {});
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.error().find("not shorter than the image"), std::string::npos);
  small.channels.pop_back();
  EXPECT_FALSE(imaging::deblur(small, coded_capture(3000, 4), {}).ok());
}

}  // namespace
}  // namespace flutterscan::sim
