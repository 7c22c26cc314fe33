#include "codes/merits.hpp"

#include <gtest/gtest.h>

#include <string>

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
