// --scheme auto's choice follows the regime map: coded light where the map
// says it wins (c = 3, noisy sensor), a short white strobe elsewhere.

#include <gtest/gtest.h>

#include "codes/scheme_choice.hpp"

namespace flutterscan::codes {
namespace {

TEST(SchemeChoice, CodedLightWhereTheMapSaysItWins) {
  const auto noisy = choose_scheme(1000, 30, 3);
  EXPECT_EQ(noisy.scheme, "found-mse");
  EXPECT_GT(noisy.margin_db, 3.0);
  EXPECT_EQ(noisy.code.leds(), 3);
  EXPECT_EQ(noisy.code.length(), 52);
  // Off-grid values go to the nearest cell on log scales: 1400 e- is nearer 1000 than 3000.
  const auto near = choose_scheme(1400, 25, 2.5);
  EXPECT_EQ(near.cell_electrons, 1000);
  EXPECT_EQ(near.cell_read_noise, 30);
  EXPECT_EQ(near.cell_cap, 3);
}

TEST(SchemeChoice, AShortStrobeForQuietSensorsAndHighOverdrive) {
  const auto quiet = choose_scheme(300, 1, 3);
  EXPECT_EQ(quiet.scheme, "snapshot-2");
  EXPECT_LT(quiet.margin_db, 0);
  int lit = 0;
  for (int t = 0; t < quiet.code.length(); ++t) lit += quiet.code.mask(t) == 7 ? 1 : 0;
  EXPECT_EQ(lit, 2);
  EXPECT_EQ(choose_scheme(1000, 30, 8).scheme.rfind("snapshot-", 0), 0u);
  EXPECT_EQ(choose_scheme(1000, 30, 8).cell_cap, 8);
}

TEST(SnapshotCode, AllThreeLedsForTheFirstKSlotsAndNothingElseByThatName) {
  const auto four = snapshot_code("snapshot-4");
  ASSERT_TRUE(four.has_value());
  ASSERT_EQ(four->length(), 52);
  for (int t = 0; t < 52; ++t) EXPECT_EQ(four->mask(t), t < 4 ? 7 : 0) << t;
  EXPECT_TRUE(snapshot_code("snapshot-52").has_value());
  for (const char* bad : {"snapshot-0", "snapshot-53", "snapshot-", "snapshot-4x", "snapshot--1",
                          "strobe-4", "seed-maxmin-1"})
    EXPECT_FALSE(snapshot_code(bad).has_value()) << bad;
}

}  // namespace
}  // namespace flutterscan::codes
