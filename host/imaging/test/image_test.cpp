// Planes (imaging/image.hpp): a part of one is the block it names, copied.

#include "imaging/image.hpp"

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

}  // namespace
}  // namespace flutterscan::imaging
