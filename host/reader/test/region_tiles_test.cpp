// Regions cut to what a frame's decode can afford (region_tiles.hpp).
#include "reader/region_tiles.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace flutterscan::reader {
namespace {

bool holds(const LabelRegion& tile, int x0, int y0, int x1, int y1) {
  return tile.begin <= x0 && tile.end >= x1 && tile.across_begin <= y0 && tile.across_end >= y1;
}

TEST(RegionTiles, AFrameOfPrintIsCutIntoTilesThatHoldEveryCodeUpToHalfATile) {
  // One region the size of a 1920 x 1080 frame (its rows not measured: every row).
  const LabelRegion print{0, 1920, true, 0, 0};
  const long long max_px = 700LL * 700;
  const std::vector<RegionTile> tiles = cut_to_tiles({&print, 1}, 1080, max_px);
  ASSERT_GT(tiles.size(), 1u);
  const int side = static_cast<int>(std::sqrt(static_cast<double>(max_px)));
  for (const RegionTile& t : tiles) {
    EXPECT_EQ(t.region, 0u);
    EXPECT_LE(t.tile.end - t.tile.begin, side);
    EXPECT_LE(t.tile.across_end - t.tile.across_begin, side);
    EXPECT_TRUE(print.contains(t.tile) || !print.rows_measured());
    EXPECT_GE(t.tile.begin, 0);
    EXPECT_LE(t.tile.end, 1920);
    EXPECT_GE(t.tile.across_begin, 0);
    EXPECT_LE(t.tile.across_end, 1080);
    // Cut where the frame's edge cuts the region: the tiles at its first or last column.
    EXPECT_EQ(t.tile.cut, t.tile.begin == 0 || t.tile.end == 1920);
    EXPECT_TRUE(t.tile.tile);  // read with kTileRowStep
  }
  // A code of half a tile each way, anywhere in the region, lies whole in a tile.
  const int half = side / 2;
  for (int y = 0; y + half <= 1080; y += 37)
    for (int x = 0; x + half <= 1920; x += 41) {
      bool whole = false;
      for (const RegionTile& t : tiles) whole = whole || holds(t.tile, x, y, x + half, y + half);
      EXPECT_TRUE(whole) << x << "," << y;
    }
}

TEST(RegionTiles, RegionsWithinTheBudgetAndEveryRegionWithoutOnePassWhole) {
  const std::vector<LabelRegion> regions = {{100, 400, false, 200, 500}, {0, 1920, true, 0, 0}};
  const std::vector<RegionTile> within = cut_to_tiles(regions, 1080, 1000LL * 1000);
  // The label (300 x 300) passes whole; the frame-wide region is cut, its tiles naming it.
  ASSERT_GT(within.size(), 2u);
  EXPECT_EQ(within[0].region, 0u);
  EXPECT_EQ(within[0].tile.begin, 100);
  EXPECT_EQ(within[0].tile.across_end, 500);
  EXPECT_FALSE(within[0].tile.tile);
  for (std::size_t i = 1; i < within.size(); ++i) EXPECT_EQ(within[i].region, 1u);
  const std::vector<RegionTile> unbounded = cut_to_tiles(regions, 1080, 0);
  ASSERT_EQ(unbounded.size(), 2u);
  EXPECT_EQ(unbounded[1].tile.end, 1920);
  // No tile smaller than kMinTileSide, however small the budget.
  for (const RegionTile& t : cut_to_tiles({&regions[1], 1}, 1080, 100))
    EXPECT_EQ(t.tile.across_end - t.tile.across_begin, kMinTileSide);
}

TEST(RegionTiles, AViewOfPrintCostsSomethingAMegapixel) {
  const double ms = view_cost_ms_per_mpx(kDefaultSymbologies, true);
  EXPECT_GT(ms, 0);
  EXPECT_TRUE(std::isfinite(ms));
}

}  // namespace
}  // namespace flutterscan::reader
