// Row levels: each row's sum and its worst stretch's mean square about the row's
// mean, as JointWiener's flat-row test reads them; the noise level made from
// them equals noise_level_mean's; a motion frame adopts the conversion's levels
// only where they describe its rows.
#include "imaging/row_levels.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "imaging/capture_model.hpp"
#include "imaging/motion_frame.hpp"

namespace flutterscan::imaging {
namespace {

Plane noise_plane(int width, int height, unsigned seed) {
  Plane p(width, height);
  std::mt19937 rng(seed);
  std::normal_distribution<float> noise(500.0f, 20.0f);
  for (float& v : p.pixels) v = noise(rng);
  return p;
}

TEST(RowLevels, ARowsWorstStretchIsTheOneThatStrays) {
  // 300 samples: two stretches of 150 (300 / 128 = 2). A constant 100 with a
  // step of +-10 in the second stretch only.
  std::vector<float> row(300, 100.0f);
  for (std::size_t x = 150; x < 300; ++x) row[x] += (x % 2 == 0) ? 10.0f : -10.0f;
  const RowLevel level = row_level(row);
  EXPECT_FLOAT_EQ(level.sum, 30000.0f);
  EXPECT_FLOAT_EQ(level.mean(row.size()), 100.0f);
  EXPECT_NEAR(level.worst_mean_square, 100.0, 1e-9);  // the second stretch's; the first's is 0
  // The worst stretch leads, wherever it lies.
  std::reverse(row.begin(), row.end());
  EXPECT_NEAR(row_level(row).worst_mean_square, 100.0, 1e-9);
  // A non-finite sample makes the row unjudgeable: no threshold passes NaN.
  row[20] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_TRUE(std::isnan(row_level(row).worst_mean_square));
  row[20] = 100.0f;
  row[299] = std::numeric_limits<float>::infinity();
  EXPECT_FALSE(row_level(row).worst_mean_square <= 1e30);
}

TEST(RowLevels, TheirNoiseLevelIsNoiseLevelMeans) {
  const Image image{{noise_plane(333, 41, 1), noise_plane(333, 41, 2)}};
  const RowLevels levels = RowLevels::of(image);
  ASSERT_TRUE(levels.fits(2, 41, 333));
  EXPECT_FALSE(levels.fits(2, 41, 332));
  EXPECT_FALSE(levels.fits(3, 41, 333));
  for (int c = 0; c < 2; ++c) {
    EXPECT_EQ(levels.mean_of_rows(c, kNoiseLevelRowStep),
              noise_level_mean(image.channels[static_cast<std::size_t>(c)]));
    for (int y = 0; y < 41; ++y) {
      const RowLevel direct = row_level(image.channels[static_cast<std::size_t>(c)].row(y));
      EXPECT_EQ(levels.at(c, y).sum, direct.sum);
      EXPECT_EQ(levels.at(c, y).worst_mean_square, direct.worst_mean_square);
    }
  }
}

TEST(RowLevels, AMotionFrameAdoptsGivenLevelsOnlyWhereTheyDescribeItsRows) {
  const Image image{{noise_plane(200, 16, 3), noise_plane(200, 16, 4), noise_plane(200, 16, 5)}};
  // Levels that are not the image's (every row's sum 1): told apart from made ones.
  RowLevels given(3, 16, 200);
  for (int c = 0; c < 3; ++c)
    for (int y = 0; y < 16; ++y) given.set(c, y, {1.0f, 0.0});
  // +x: the rows are the camera's; the levels given are taken as they are.
  auto plus_x = MotionFrame::make(image, Direction::kPlusX, PixelValues::kScan, given);
  ASSERT_TRUE(plus_x.ok()) << plus_x.error();
  EXPECT_EQ(plus_x.value().row_levels().at(2, 15).sum, 1.0f);
  // -x: the rows are reversed, the levels given are the camera rows': made again.
  auto minus_x = MotionFrame::make(image, Direction::kMinusX, PixelValues::kScan, given);
  ASSERT_TRUE(minus_x.ok()) << minus_x.error();
  EXPECT_EQ(minus_x.value().row_levels().at(2, 15).sum,
            row_level(minus_x.value().channel(2).row(15)).sum);
  // Levels of another size: made again; none given: made.
  auto other =
      MotionFrame::make(image, Direction::kPlusX, PixelValues::kScan, RowLevels(3, 15, 200));
  ASSERT_TRUE(other.ok());
  EXPECT_EQ(other.value().row_levels().at(0, 3).sum, row_level(image.channels[0].row(3)).sum);
  auto made = MotionFrame::make(image, Direction::kPlusY);
  ASSERT_TRUE(made.ok());
  EXPECT_TRUE(made.value().row_levels().fits(3, 200, 16));  // transposed: 200 rows of 16
}

}  // namespace
}  // namespace flutterscan::imaging
