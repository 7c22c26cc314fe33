#include "codes/merits.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "codes/spectrum.hpp"

namespace flutterscan::codes {
namespace {

LedCode code3(std::string_view digits) {
  auto code = LedCode::parse(digits, 3, CodeRule::kOneOfN);
  EXPECT_TRUE(code.ok());
  return code.value();
}

double merit(Merit m, const LedCode& code, const MeritSettings& settings = {}) {
  const auto value = evaluate_merit(m, code, settings);
  EXPECT_TRUE(value.ok()) << value.error();
  return value.value();
}

// The seed's published merits (sections 5.1), to 4 decimals.
TEST(SeedMerits, MaxMinCodesReproduce) {
  EXPECT_NEAR(merit(Merit::kMaxMin, code3("2212441414112412441224111241244244242212442211444144")),
              -21.4382, 5e-5);
  EXPECT_NEAR(merit(Merit::kMaxMin, code3("1212222141422244221122444224241121424422424241241242")),
              -21.5469, 5e-5);
  EXPECT_NEAR(merit(Merit::kMaxMin, code3("2211424222421411121144411124121212214214141122112142")),
              -21.7312, 5e-5);
}

TEST(SeedMerits, AvgMinCodeReproduces) {
  EXPECT_NEAR(merit(Merit::kAvgMin, code3("2212144111241224412411211221241444112124441212442242")),
              -25.6353, 5e-5);
}

TEST(SeedMerits, CorrectedPairsCodeReproduces) {
  // The seed prints 53 digits; removing the '1' at index 48 gives its score exactly.
  EXPECT_NEAR(merit(Merit::kPairs, code3("2221421124421222111122142141211244121242241114221211")),
              -21.6372, 5e-5);
}

TEST(SeedMerits, RaskarCodeOnTheSeedGrid) {
  const auto raskar = LedCode::parse("1010000111000001010000110011110111010111001001100111", 1);
  ASSERT_TRUE(raskar.ok());
  EXPECT_NEAR(merit(Merit::kMaxMin, raskar.value()), -25.4359, 5e-5);
}

}  // namespace
}  // namespace flutterscan::codes

namespace flutterscan::codes {
namespace {

TEST(SeedMerits, PairsCodeThirdSequenceHasAnExactNull) {
  const auto code = code3("2221421124421222111122142141211244121242241114221211");
  const auto grid = seed_grid_spectrum(led_sequence(code, 2));
  EXPECT_EQ(grid.db.back(), kNullDb);  // at f = 0.5: the pairs merit never looks at it
}

TEST(SeedMerits, SequencesMapToBitsNotToTheProse) {
  // The seed's printed S1 of the max-min code is not bit 0; bit 2 holds the best sequence.
  const auto code = code3("2212441414112412441224111241244244242212442211444144");
  const auto best = seed_grid_spectrum(led_sequence(code, 2));
  EXPECT_NEAR(*std::min_element(best.db.begin(), best.db.end()), -21.4382, 5e-5);
}

TEST(JointMerit, RectWhiteAtDcCollectsTheWholeBudget) {
  const auto rect_white = LedCode::parse(std::string(52, '7'), 3).value();
  LightModel light;  // E 3000, c 3, read noise 4
  const double expected = 3 * 3000.0 * 3000.0 / (3000.0 + 16.0);
  EXPECT_NEAR(joint_information(rect_white, light, 0.0), expected, 1e-6);
  // A rect exposure has exact nulls: its joint merit is zero.
  EXPECT_NEAR(merit(Merit::kJoint, rect_white), 0.0, 1e-6);
}

TEST(JointMerit, CapLimitsAShortStrobe) {
  // One slot of white light: I = min(E / 1, c E / L) = c E / L.
  std::string strobe(52, '0');
  strobe[0] = '7';
  const auto code = LedCode::parse(strobe, 3).value();
  LightModel light;
  const double intensity = 3.0 * 3000.0 / 52.0;
  const double expected = 3 * intensity * intensity / (intensity + 16.0);
  EXPECT_NEAR(joint_information(code, light, 0.3), expected, 1e-9);
  light.cap = 52;  // uncapped: the whole budget in one slot
  EXPECT_NEAR(joint_information(code, light, 0.3), 3 * 3000.0 * 3000.0 / 3016.0, 1e-6);
}

TEST(JointMerit, IdentityCrosstalkEqualsNone) {
  const auto code = code3("2212441414112412441224111241244244242212442211444144");
  MeritSettings plain;
  MeritSettings identity;
  identity.light.crosstalk = Crosstalk{3, 3, {1, 0, 0, 0, 1, 0, 0, 0, 1}};
  EXPECT_NEAR(merit(Merit::kJoint, code, plain), merit(Merit::kJoint, code, identity), 1e-9);
  EXPECT_NEAR(merit(Merit::kJoint, code, plain), 19.688, 0.01);
}

TEST(JointMerit, CrosstalkCostsInformation) {
  const auto code = code3("2211424222421411121144411124121212214214141122112142");
  MeritSettings mixed;
  mixed.light.crosstalk = Crosstalk{3, 3, {0.90, 0.08, 0.01, 0.10, 0.85, 0.12, 0.01, 0.07, 0.88}};
  EXPECT_LT(merit(Merit::kJoint, code, mixed), merit(Merit::kJoint, code));
}

TEST(JointMerit, MoreLightMoreInformationLessError) {
  const auto code = code3("2211424222421411121144411124121212214214141122112142");
  MeritSettings dim;
  dim.light.electrons = 300;
  EXPECT_LT(merit(Merit::kJoint, code, dim), merit(Merit::kJoint, code));
  EXPECT_GT(merit(Merit::kMse, code, dim), merit(Merit::kMse, code));
}

TEST(Merits, SingleMeritIsMinimumOfNormalisedPaddedDft) {
  const auto raskar = LedCode::parse("1010000111000001010000110011110111010111001001100111", 1);
  const double single = merit(Merit::kSingle, raskar.value());
  EXPECT_GT(single, 0.04);
  EXPECT_LT(single, 26.0 / 26.0);
  const auto rect = LedCode::parse(std::string(52, '1'), 1).value();
  EXPECT_LT(merit(Merit::kSingle, rect), 1e-3);  // near-nulls of the box
}

TEST(Merits, InapplicableMeritsSayWhy) {
  const auto raskar = LedCode::parse("1010", 1).value();
  const auto pairs = evaluate_merit(Merit::kPairs, raskar, {});
  ASSERT_FALSE(pairs.ok());
  EXPECT_NE(pairs.error().find("3 LEDs"), std::string::npos);
  const auto single = evaluate_merit(Merit::kSingle, code3("124"), {});
  ASSERT_FALSE(single.ok());
  MeritSettings bad;
  bad.light.crosstalk = Crosstalk{3, 2, {1, 0, 0, 1, 0, 0}};
  const auto joint = evaluate_merit(Merit::kJoint, code3("124"), bad);
  ASSERT_FALSE(joint.ok());
  EXPECT_NE(joint.error().find("2 columns"), std::string::npos);
}

TEST(Merits, NamesRoundTrip) {
  for (Merit m : kAllMerits) EXPECT_EQ(merit_from_name(merit_name(m)), m);
  EXPECT_FALSE(merit_from_name("bogus"));
}

TEST(Merits, ObjectiveRoundTripsAndOrdersMseLowerIsBetter) {
  for (Merit m : kAllMerits)
    EXPECT_NEAR(merit_from_objective(m, merit_objective(m, 0.25)), 0.25, 1e-12);
  EXPECT_GT(merit_objective(Merit::kMse, 0.001), merit_objective(Merit::kMse, 0.002));
  EXPECT_GT(merit_objective(Merit::kJoint, 200), merit_objective(Merit::kJoint, 100));
}

}  // namespace
}  // namespace flutterscan::codes
