#include "flutterscan/common/led_code.hpp"

#include <gtest/gtest.h>

#include <string>

namespace flutterscan {
namespace {

constexpr std::string_view kSeedMaxMin = "2212441414112412441224111241244244242212442211444144";
constexpr std::string_view kRaskar = "1010000111000001010000110011110111010111001001100111";

std::string message(const CodeIssue& issue) {
  char buffer[160];
  describe(issue, buffer);
  return buffer;
}

std::string text(const LedCode& code) {
  std::string out(static_cast<std::size_t>(code.length()), '?');
  EXPECT_EQ(code.format(out), out.size());
  return out;
}

TEST(LedCode, ParsesAndFormatsTheSeedNotation) {
  const auto code = LedCode::parse(kSeedMaxMin, 3, CodeRule::kOneOfN);
  ASSERT_TRUE(code.ok()) << message(code.error());
  EXPECT_EQ(code.value().length(), 52);
  EXPECT_EQ(code.value().leds(), 3);
  EXPECT_EQ(code.value().mask(0), 2);
  EXPECT_EQ(code.value().mask(3), 2);
  EXPECT_EQ(code.value().mask(4), 4);
  EXPECT_TRUE(code.value().is_on(4, 2));
  EXPECT_FALSE(code.value().is_on(4, 0));
  EXPECT_EQ(text(code.value()), kSeedMaxMin);
}

TEST(LedCode, OneLedCodeIsAPlainBitString) {
  const auto code = LedCode::parse(kRaskar, 1);
  ASSERT_TRUE(code.ok());
  EXPECT_EQ(code.value().on_slots(0), 26);
  EXPECT_FLOAT_EQ(code.value().duty_cycle(0), 0.5f);
  EXPECT_EQ(text(code.value()), kRaskar);
}

TEST(LedCode, AllLedsTogetherIsWrittenWithSevens) {
  const auto code = LedCode::parse("7070", 3);
  ASSERT_TRUE(code.ok());
  for (int led = 0; led < 3; ++led) EXPECT_EQ(code.value().on_slots(led), 2);
  EXPECT_FALSE(code.value().is_one_of_n());
  const auto issue = code.value().check_one_of_n();
  EXPECT_EQ(issue.slot, 0);
  EXPECT_EQ(message(issue), "slot 0: digit 7 lights three LEDs in a one-of-3 code");
}

TEST(LedCode, UpperCaseHexDigitsAreAccepted) {
  const auto code = LedCode::parse("F8", 4);
  ASSERT_TRUE(code.ok());
  EXPECT_EQ(code.value().mask(0), 15);
  EXPECT_EQ(text(code.value()), "f8");
}

TEST(LedCode, OneOfNViolationNamesTheSlot) {
  std::string digits(kSeedMaxMin);
  digits[17] = '3';
  const auto code = LedCode::parse(digits, 3, CodeRule::kOneOfN);
  ASSERT_FALSE(code.ok());
  EXPECT_EQ(code.error().error, CodeError::kNotOneOfN);
  EXPECT_EQ(code.error().slot, 17);
  EXPECT_EQ(message(code.error()), "slot 17: digit 3 lights two LEDs in a one-of-3 code");
}

TEST(LedCode, DarkSlotIsNotOneOfN) {
  const auto code = LedCode::parse("1240", 3, CodeRule::kOneOfN);
  ASSERT_FALSE(code.ok());
  EXPECT_EQ(message(code.error()), "slot 3: digit 0 lights no LED in a one-of-3 code");
}

TEST(LedCode, AnyMaskRuleAcceptsDarkAndWhiteSlots) {
  EXPECT_TRUE(LedCode::parse("1240", 3).ok());
  EXPECT_TRUE(LedCode::parse("7777", 3).ok());
}

TEST(LedCode, RejectsCharacterThatIsNotADigit) {
  const auto code = LedCode::parse("1212x4", 3);
  ASSERT_FALSE(code.ok());
  EXPECT_EQ(code.error().error, CodeError::kNotADigit);
  EXPECT_EQ(message(code.error()), "slot 4: 'x' is not a digit of the code notation (0-9, a-f)");
}

TEST(LedCode, RejectsDigitNamingAMissingLed) {
  const auto code = LedCode::parse("12184", 3);
  ASSERT_FALSE(code.ok());
  EXPECT_EQ(code.error().error, CodeError::kNoSuchLed);
  EXPECT_EQ(code.error().slot, 3);
  EXPECT_EQ(message(code.error()),
            "slot 3: digit 8 lights LED 3, but the code has 3 LEDs (LED 0 to 2)");
  const auto single = LedCode::parse("1012", 1);
  ASSERT_FALSE(single.ok());
  EXPECT_EQ(message(single.error()),
            "slot 3: digit 2 lights LED 1, but the code has 1 LED (LED 0)");
}

TEST(LedCode, RejectsEmptyTooLongAndBadLedCount) {
  EXPECT_EQ(message(LedCode::parse("", 3).error()),
            "the code is empty: it needs at least one slot");
  EXPECT_EQ(message(LedCode::parse(std::string(257, '1'), 1).error()),
            "the code has 257 slots; at most 256 are allowed");
  EXPECT_TRUE(LedCode::parse(std::string(256, '1'), 1).ok());
  EXPECT_EQ(message(LedCode::parse("12", 5).error()), "a code has 1 to 4 LEDs, not 5");
  EXPECT_EQ(message(LedCode::parse("12", 0).error()), "a code has 1 to 4 LEDs, not 0");
}

TEST(LedCode, ComplementFlipsEveryLed) {
  const auto raskar = LedCode::parse(kRaskar, 1).value();
  const LedCode inverse = raskar.complement();
  EXPECT_EQ(inverse.on_slots(0), 26);
  EXPECT_EQ(text(inverse), "0101111000111110101111001100001000101000110110011000");
  EXPECT_EQ(inverse.complement(), raskar);
  const auto triplet = LedCode::parse("124", 3).value();
  EXPECT_EQ(text(triplet.complement()), "653");
}

TEST(LedCode, DutyCyclesOfAOneOfThreeCodeSumToOne) {
  const auto code = LedCode::parse(kSeedMaxMin, 3).value();
  const int total = code.on_slots(0) + code.on_slots(1) + code.on_slots(2);
  EXPECT_EQ(total, 52);
  EXPECT_NEAR(code.duty_cycle(0) + code.duty_cycle(1) + code.duty_cycle(2), 1.0f, 1e-6f);
}

TEST(LedCode, FromMasksChecksLikeParse) {
  const std::uint8_t masks[] = {1, 2, 4, 3};
  EXPECT_TRUE(LedCode::from_masks(masks, 3).ok());
  const auto strict = LedCode::from_masks(masks, 3, CodeRule::kOneOfN);
  ASSERT_FALSE(strict.ok());
  EXPECT_EQ(strict.error().slot, 3);
}

TEST(LedCode, FormatRefusesAShortBuffer) {
  const auto code = LedCode::parse("1242", 3).value();
  char small[3];
  EXPECT_EQ(code.format(small), 0u);
}

TEST(LedCode, DescribeTruncatesSafely) {
  const auto issue = LedCode::parse("1212x4", 3).error();
  char tiny[8];
  EXPECT_EQ(describe(issue, tiny), 7u);
  EXPECT_EQ(std::string(tiny), "slot 4:");
}

}  // namespace
}  // namespace flutterscan
