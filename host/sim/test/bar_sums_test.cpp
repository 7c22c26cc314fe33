// Sums along a linear code's bars (imaging/bar_sums.hpp): the bars' slope is
// found on a latent, a frame's rows summed along it are a frame of the same
// bars at 17 times the light through the same PSFs, and their model says so.

#include "imaging/bar_sums.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "imaging/deblur.hpp"
#include "imaging/frame_conversion.hpp"
#include "imaging/metrics.hpp"
#include "sim/forward_model.hpp"

namespace flutterscan::imaging {
namespace {

/// Bars 2-6 px wide (ink 0.06, paper 0.9) across rows [top, height - top)
/// along `bars` (its origin taken as the plane's centre): each point shows the
/// pattern where its bar crosses the middle row; belt grey 0.35 above and below.
Plane tilted_bars(int width, int height, BarSlope bars, unsigned seed) {
  bars.origin_x = width / 2.0;
  bars.origin_y = height / 2.0;
  std::mt19937 rng(seed);
  std::vector<float> pattern(static_cast<std::size_t>(2 * width));
  for (std::size_t x = 0; x < pattern.size();) {
    const int run = 2 + static_cast<int>(rng() % 5);
    const float value = (rng() % 2) ? 0.9f : 0.06f;
    for (int i = 0; i < run && x < pattern.size(); ++i, ++x) pattern[x] = value;
  }
  Plane p(width, height, 0.35f);
  const int top = height / 8;
  constexpr int kSub = 8;  // each pixel the mean of 8 points across it: edges as a sensor sees them
  for (int y = top; y < height - top; ++y)
    for (int x = 0; x < width; ++x) {
      float sum = 0;
      for (int i = 0; i < kSub; ++i) {
        const double px = x + (i + 0.5) / kSub, py = y + 0.5;
        const double u = px - bars.at(px, py) * (py - bars.origin_y) + width / 2.0;
        sum += pattern[static_cast<std::size_t>(std::clamp(u, 0.0, 2.0 * width - 1))];
      }
      p.at(x, y) = sum / kSub;
    }
  return p;
}

CaptureModel coded_capture(double electrons) {
  CaptureModel m;
  m.code = LedCode::parse("2212441414112412441224111241244244242212442211444144", 3).value();
  m.blur_px = 52;
  m.led_electrons = budgeted_led_electrons(m.code, electrons, 3);
  m.read_noise = 4;
  m.full_well = 1e9;
  m.bit_depth = 16;
  return m;
}

/// `scene` captured at `electrons` (coded_capture()) and the frame deblurred by joint Wiener.
struct Captured {
  CaptureModel model;
  Image frame;
  Plane direct;  ///< joint Wiener's latent of the frame
};
Captured capture(const Plane& scene, double electrons) {
  Captured c{coded_capture(electrons), {}, {}};
  c.frame = dn_to_electrons(sim::record_frame(sim::expected_electrons(scene, c.model), c.model, 9),
                            c.model);
  const auto direct = deblur(c.frame, c.model, DeblurOptions{});
  EXPECT_TRUE(direct.ok());
  if (direct.ok()) c.direct = direct.value().latent;
  return c;
}

/// PSNR over the rows `margin` or more inside the bars (where every summed row is a bar's).
double psnr_inside_bars(const Plane& scene, const Plane& latent, int margin) {
  auto region = scored_region(scene.width, scene.height, 52, Direction::kPlusX);
  region.y0 = scene.height / 8 + margin;
  region.y1 = scene.height - scene.height / 8 - margin;
  return psnr(scene, latent, region);
}

TEST(BarSums, TheSlopeFoundIsTheBarsAndZeroForUprightBars) {
  for (const double slope : {0.0, 0.2, -0.33}) {
    const Plane scene = tilted_bars(400, 160, {.at_origin = slope}, 3);
    const BarSlope found = bar_slope(scene, 16);
    EXPECT_NEAR(found.at(200, 80), slope, 0.011) << slope;
    EXPECT_NEAR(found.per_column * scene.width, 0, 0.011) << slope;  // parallel: no perspective
  }
}

TEST(BarSums, BarsInPerspectiveAreFoundAsLinesThroughOnePoint) {
  // A label's bars meeting 2000 rows below its centre and 600 columns right of
  // it, or 4000 rows above and 400 right: from one edge to the other their
  // slope changes by 0.2 or -0.1.
  for (const auto& [slope, change] : {std::pair{-0.3, 0.2}, std::pair{0.1, -0.1}}) {
    const Plane scene = tilted_bars(400, 160, {.at_origin = slope, .per_column = change / 400}, 7);
    const BarSlope found = bar_slope(scene, 16);
    EXPECT_NEAR(found.at(200, 80), slope, 0.011) << slope;
    EXPECT_NEAR(found.per_column * scene.width, change, 0.011) << slope;
  }
}

TEST(BarSums, TheSlopeIsJudgedWhereTheBarsAreNotOverTheWholeWindow) {
  // A short code (bars sloping 0.25, 48 rows by 192 columns) on a board whose
  // own stripes (contrast 0.3, 6 px wide, sloping -0.2: corrugation, grain)
  // fill the rest of the window: over the whole window the stripes' slope
  // keeps the most contrast (-0.2 found), over the code's tiles the bars'.
  const int width = 480, height = 320;
  const Plane code = tilted_bars(192, 64, {.at_origin = 0.25}, 11);
  Plane window(width, height);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const double u = x + 0.2 * (y - height / 2) + 1000;
      window.at(x, y) = static_cast<int>(u / 6) % 2 ? 0.6f : 0.3f;
    }
  for (int y = 8; y < 56; ++y)
    for (int x = 0; x < 192; ++x) window.at(100 + x, 60 + y - 8) = code.at(x, y);
  const BarSlope found = bar_slope(window, 16);
  EXPECT_NEAR(found.at(196, 84), 0.25, 0.011);
}

TEST(BarSums, SumsAreOfTheBarsOnlyWhereAllTheirRowsCrossThem) {
  // Bars sloping 0.1 on rows [60, 132); under them a line of digits (strokes
  // 14 rows tall, sloping as the bars: the same print); a dark board beyond an
  // edge at column 300 on every row. Rows whose 49 rows summed all cross the
  // bars: [84, 108]; not the digits' (whose sums along the slope look like
  // bars, 14 rows of them) nor the edge's (the same on every row).
  const int width = 320, height = 240;
  const Plane code = tilted_bars(256, 96, {.at_origin = 0.1}, 13);
  Plane label(width, height, 0.85f);
  for (int y = 60; y < 132; ++y)  // the code's bars: its rows [12, 84)
    for (int x = 0; x < 256; ++x) label.at(24 + x, y) = code.at(x, y - 60 + 12);
  std::mt19937 rng(5);
  for (int digit = 0; digit < 24; ++digit)
    for (int stroke = 0; stroke < 2; ++stroke) {
      const int x0 = 30 + digit * 10 + static_cast<int>(rng() % 6), top = 148;
      for (int y = top; y < top + 14; ++y)
        for (int x = x0; x < x0 + 2; ++x) label.at(x + static_cast<int>(0.1 * (y - 100)), y) = 0.1f;
    }
  for (int y = 0; y < height; ++y)
    for (int x = 300; x < width; ++x) label.at(x, y) = 0.08f;
  const BarSlope found = bar_slope(label, 16);
  ASSERT_NEAR(found.at(152, 100), 0.1, 0.011);
  const std::vector<bool> across = rows_across_bars(label, found, 24);
  ASSERT_EQ(across.size(), static_cast<std::size_t>(height));
  for (int y = 0; y < height; ++y) {
    if (y >= 84 && y <= 108) {
      EXPECT_TRUE(across[static_cast<std::size_t>(y)]) << y;
    } else if (y < 60 || y >= 132) {
      EXPECT_FALSE(across[static_cast<std::size_t>(y)]) << y;
    }
  }
}

TEST(BarSums, SumsAreOfOneCodeOnlyWhereAllTheirRowsCrossIt) {
  // Two codes stacked, their bars sloping alike (rows [40, 100) and [100, 160)):
  // summed 8 either side, rows [93, 107) mix the two, bars on every row; those
  // within 4 of the codes' border mix in 4 rows or more of the other code.
  const Plane upper = tilted_bars(256, 96, {.at_origin = -0.1}, 17);
  const Plane lower = tilted_bars(256, 96, {.at_origin = -0.1}, 19);
  Plane label(288, 200, 0.85f);
  for (int y = 40; y < 160; ++y)
    for (int x = 0; x < 256; ++x)
      label.at(16 + x, y) = y < 100 ? upper.at(x, y - 40 + 18) : lower.at(x, y - 100 + 18);
  const BarSlope found = bar_slope(label, 16);
  ASSERT_NEAR(found.at(144, 100), -0.1, 0.011);
  const std::vector<bool> across = rows_across_bars(label, found, 8);
  for (int y = 0; y < 200; ++y) {
    const bool one_code = (y >= 48 && y <= 91) || (y >= 108 && y <= 151);
    if (one_code || (y >= 96 && y < 104)) {
      EXPECT_EQ(across[static_cast<std::size_t>(y)], one_code) << y;
    }
  }
}

TEST(BarSums, RowsSumAlongTheSlopeAndNearTheEdgesScaleToAFullSum) {
  Plane ramp(64, 40);
  for (int y = 0; y < ramp.height; ++y)
    for (int x = 0; x < ramp.width; ++x) ramp.at(x, y) = static_cast<float>(x);
  Image one{{ramp}};
  // Slope 1: row k away is read k px further along; the shifts cancel in the
  // sum about the row itself, so away from the ends the sum is 5 x the column.
  const Image sums = sum_along_bars(one, {.at_origin = 1.0}, 2);
  for (const int y : {2, 20, 37}) EXPECT_NEAR(sums.channels[0].at(30, y), 5 * 30.0, 1e-3) << y;
  // The first row sums rows 0-2 (read at 30, 31, 32), scaled from 3 rows to 5.
  EXPECT_NEAR(sums.channels[0].at(30, 0), (30 + 31 + 32) * 5 / 3.0, 1e-3);
  // Where rows are missing (first row: 3 of 5) the sum is scaled to five.
  Image constant{{Plane(16, 10, 2.0f)}};
  const Image scaled = sum_along_bars(constant, {.at_origin = 0.3}, 2);
  for (const int y : {0, 1, 5, 9}) EXPECT_NEAR(scaled.channels[0].at(8, y), 10.0, 1e-4) << y;
  // Beyond a row's ends, its end sample: a constant stays constant to the last column.
  EXPECT_NEAR(scaled.channels[0].at(15, 5), 10.0, 1e-4);
}

TEST(BarSums, RowsSumAlongBarsInPerspective) {
  // One row a ramp (each sample its column), the rest 0: the sums 2 rows above
  // and below it read the ramp where the bars through them cross it, at
  // x + k at(x, y) (linear along a row: the interpolation is exact). Along the
  // slope at the origin instead, a fifth of a pixel off 28 columns from it.
  const BarSlope fan{.at_origin = 0.2, .per_column = 0.004, .origin_x = 32, .origin_y = 20};
  Plane one_row(64, 40, 0.0f);
  for (int x = 0; x < one_row.width; ++x) one_row.at(x, 22) = static_cast<float>(x);
  const Image image{{one_row}};
  const Image sums = sum_along_bars(image, fan, 2);
  const Image parallel = sum_along_bars(image, {.at_origin = 0.2}, 2);
  for (const auto& [y, k] : {std::pair{20, 2}, std::pair{24, -2}})
    for (const int x : {4, 32, 60}) {
      const double crossing = x + k * fan.at(x, y);
      EXPECT_NEAR(sums.channels[0].at(x, y), crossing, 1e-3) << x << "," << y;
      EXPECT_NEAR(parallel.channels[0].at(x, y), x + k * 0.2, 1e-3) << x << "," << y;
      if (x != 32) {
        EXPECT_GT(std::abs(crossing - (x + k * 0.2)), 0.2) << x << "," << y;
      }
    }
  // Beyond a row's ends, its end sample: a constant stays constant at every column.
  const Image constant = sum_along_bars(Image{{Plane(64, 40, 2.0f)}}, fan, 8);
  for (int y = 0; y < 40; ++y)
    for (int x = 0; x < 64; ++x)
      ASSERT_NEAR(constant.channels[0].at(x, y), 34.0, 1e-3) << x << "," << y;
}

TEST(BarSums, TheModelOfSumsHasTheSumsLightAndNoise) {
  const CaptureModel m = coded_capture(300);
  const CaptureModel sums = model_of_row_sums(m, 17);
  for (int c = 0; c < 3; ++c)
    EXPECT_NEAR(channel_white_electrons(sums, c), 17 * channel_white_electrons(m, c), 1e-6);
  EXPECT_NEAR(channel_noise_variance(sums, 17 * 120.0), 17 * channel_noise_variance(m, 120.0),
              1e-9);
}

TEST(BarSums, TiltedBarsInDimLightDeblurFarBetterFromTheirSums) {
  const double slope = 0.2;
  const Plane scene = tilted_bars(512, 160, {.at_origin = slope}, 5);
  const Captured c = capture(scene, 300);
  const BarSlope found = bar_slope(c.direct, 16);
  EXPECT_NEAR(found.at(256, 80), slope, 0.02);
  const auto summed =
      deblur(sum_along_bars(c.frame, found, 8), model_of_row_sums(c.model, 17), DeblurOptions{});
  ASSERT_TRUE(summed.ok());
  const double before = psnr_inside_bars(scene, c.direct, 8);
  const double after = psnr_inside_bars(scene, summed.value().latent, 8);
  // 17 rows: the noise's rms a quarter; the Wiener prior's own error on 2 px
  // bars then bounds it (measured: 16.8 -> 22.4 dB; the sums without noise 22.9).
  EXPECT_GT(after, before + 4) << before << " -> " << after;
}

TEST(BarSums, BarsInPerspectiveDeblurBetterSummedAlongTheirOwnSlopes) {
  // Slope 0.15 at the centre, 0.1 less at one edge than the other (as on the
  // real-print photo ean13-2-05) at 1000 e-. Along one slope, a bar 256
  // columns from the origin is 1.2 px off 24 rows away: 49 rows summed so
  // deblur worse than 17 (measured 23.6 against 24.0 dB); along the bars' own
  // slopes better (24.8; the Wiener prior's error on 2 px bars bounds both).
  const Plane scene = tilted_bars(512, 160, {.at_origin = 0.15, .per_column = -0.1 / 512}, 5);
  const Captured c = capture(scene, 1000);
  const BarSlope found = bar_slope(c.direct, 24);
  EXPECT_NEAR(found.at(256, 80), 0.15, 0.011);
  EXPECT_NEAR(found.per_column * scene.width, -0.1, 0.011);
  BarSlope parallel = found;
  parallel.per_column = 0;
  auto summed = [&](const BarSlope& slope, int half_rows) {
    const auto sums = deblur(sum_along_bars(c.frame, slope, half_rows),
                             model_of_row_sums(c.model, 2 * half_rows + 1), DeblurOptions{});
    EXPECT_TRUE(sums.ok());
    return sums.ok() ? psnr_inside_bars(scene, sums.value().latent, 24) : 0.0;
  };
  const double own17 = summed(found, 8), own49 = summed(found, 24);
  const double one17 = summed(parallel, 8), one49 = summed(parallel, 24);
  EXPECT_GT(own49, one49 + 0.8) << one49 << " -> " << own49;
  EXPECT_GT(own49, own17 + 0.4) << own17 << " -> " << own49;
  EXPECT_LT(one49, one17) << one17 << " -> " << one49;
}

}  // namespace
}  // namespace flutterscan::imaging
