#include "codes/spectrum.hpp"

#include <gtest/gtest.h>

namespace flutterscan::codes {
namespace {

TEST(Spectrum, SeedGridIsFirstPowerOfTwoAbove) {
  EXPECT_EQ(seed_grid_size(52), 64);
  EXPECT_EQ(seed_grid_size(64), 128);
  EXPECT_EQ(seed_grid_size(1), 2);
}

}  // namespace
}  // namespace flutterscan::codes
