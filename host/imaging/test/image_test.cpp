// Planes (imaging/image.hpp): a part of one is the block it names, copied; a
// value between samples is bilinear (imaging/bilinear.hpp), none off the plane.

#include "imaging/image.hpp"
#include "imaging/bilinear.hpp"

#include <cmath>

#include <gtest/gtest.h>

namespace flutterscan::imaging {
namespace {

TEST(Plane, APartIsTheBlockItNamesCopied) {
  Plane p(7, 5);
  for (int y = 0; y < p.height; ++y)
    for (int x = 0; x < p.width; ++x) p.at(x, y) = static_cast<float>(10 * y + x);
  Plane part = p.part(2, 1, 6, 4);  // columns 2-5 of rows 1-3
  ASSERT_EQ(part.width, 4);
  ASSERT_EQ(part.height, 3);
  for (int y = 0; y < part.height; ++y)
    for (int x = 0; x < part.width; ++x)
      EXPECT_EQ(part.at(x, y), static_cast<float>(10 * (y + 1) + x + 2)) << x << ", " << y;
  part.at(0, 0) = -1;  // a copy: the plane keeps its own
  EXPECT_EQ(p.at(2, 1), 12.0f);
  EXPECT_EQ(p.part(0, 0, p.width, p.height).pixels, p.pixels);
  EXPECT_TRUE(p.part(3, 2, 3, 2).empty());
}

TEST(Plane, BilinearInterpolatesBetweenSamplesAndNothingOffThePlane) {
  Plane p(3, 2);
  for (int y = 0; y < p.height; ++y)
    for (int x = 0; x < p.width; ++x) p.at(x, y) = static_cast<float>(10 * y + x);
  EXPECT_DOUBLE_EQ(*bilinear(p, 0, 0), 0.0);
  EXPECT_DOUBLE_EQ(*bilinear(p, 1.25, 0.5), 6.25);
  EXPECT_DOUBLE_EQ(*bilinear(p, 2, 1), 12.0);  // the last sample is on the plane
  EXPECT_FALSE(bilinear(p, -0.01, 0.5));
  EXPECT_FALSE(bilinear(p, 2.01, 0.5));
  EXPECT_FALSE(bilinear(p, 1, 1.01));
  EXPECT_FALSE(bilinear(p, std::nan(""), 0.5));
  EXPECT_FALSE(bilinear(Plane{}, 0, 0));
  // Not clamped: an overshooting latent keeps its overshoot.
  p.at(1, 0) = -0.5f;
  EXPECT_DOUBLE_EQ(*bilinear(p, 1, 0), -0.5);
  // One sample high: along x only.
  Plane row(4, 1);
  row.at(2, 0) = 1;
  EXPECT_DOUBLE_EQ(*bilinear(row, 1.5, 0), 0.5);
  EXPECT_FALSE(bilinear(row, 1.5, 0.5));
}

}  // namespace
}  // namespace flutterscan::imaging
