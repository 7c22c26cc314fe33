#include "flutterscan/common/sequencer.hpp"

#include <gtest/gtest.h>

#include <array>

namespace flutterscan {
namespace {

const LedPinMap kPins012{3, {0, 1, 2, 0}};
const LedPinMap kPinsSpread{3, {5, 9, 12, 0}};

LedCode code(std::string_view digits, int leds) {
  return LedCode::parse(digits, leds).value();
}

TEST(Sequencer, WordSetsTheSlotsLedsAndResetsTheOthers) {
  EXPECT_EQ(bsrr_for_mask(1, kPins012), 0x00060001u);
  EXPECT_EQ(bsrr_for_mask(2, kPins012), 0x00050002u);
  EXPECT_EQ(bsrr_for_mask(4, kPins012), 0x00030004u);
  EXPECT_EQ(bsrr_for_mask(7, kPins012), 0x00000007u);
  EXPECT_EQ(bsrr_all_off(kPins012), 0x00070000u);
  EXPECT_EQ(bsrr_for_mask(2, kPinsSpread), (1u << 9) | ((1u << 5 | 1u << 12) << 16));
  EXPECT_EQ(bsrr_all_off(kPinsSpread), (1u << 5 | 1u << 9 | 1u << 12) << 16);
}

TEST(Sequencer, TableIsOneWordPerSlotThenAllOff) {
  std::array<std::uint32_t, 8> words{};
  const auto schedule = build_slot_table(code("1240", 3), 25, kPins012, words);
  ASSERT_TRUE(schedule.ok());
  EXPECT_EQ(schedule.value().word_count, 5);
  EXPECT_EQ(schedule.value().slot_time_us, 25u);
  EXPECT_EQ(schedule.value().duration_us, 100u);
  EXPECT_EQ(words[0], 0x00060001u);
  EXPECT_EQ(words[1], 0x00050002u);
  EXPECT_EQ(words[2], 0x00030004u);
  EXPECT_EQ(words[3], 0x00070000u);
  EXPECT_EQ(words[4], 0x00070000u);
  EXPECT_EQ(words[5], 0u);  // untouched
}

TEST(Sequencer, OneLedCodeResetsEveryMappedLed) {
  std::array<std::uint32_t, 3> words{};
  ASSERT_TRUE(build_slot_table(code("10", 1), 1, kPins012, words).ok());
  EXPECT_EQ(words[0], 0x00060001u);
  EXPECT_EQ(words[1], 0x00070000u);
}

TEST(Sequencer, RefusesWhatItCannotPlay) {
  std::array<std::uint32_t, kMaxSlotWords> words{};
  const LedCode c = code("124", 3);
  EXPECT_EQ(build_slot_table(c, 0, kPins012, words).error(), SequencerStatus::kSlotTimeOutOfRange);
  EXPECT_EQ(build_slot_table(c, 10'001, kPins012, words).error(),
            SequencerStatus::kSlotTimeOutOfRange);
  EXPECT_TRUE(build_slot_table(c, 1, kPins012, words).ok());
  EXPECT_TRUE(build_slot_table(c, 10'000, kPins012, words).ok());
  EXPECT_EQ(build_slot_table(c, 10, kPins012, std::span(words).first(3)).error(),
            SequencerStatus::kBufferTooSmall);
  EXPECT_EQ(build_slot_table(c, 10, LedPinMap{2, {0, 1}}, words).error(),
            SequencerStatus::kCodeHasMoreLeds);
  EXPECT_EQ(build_slot_table(c, 10, LedPinMap{3, {0, 1, 1}}, words).error(),
            SequencerStatus::kBadPinMap);
  EXPECT_EQ(build_slot_table(c, 10, LedPinMap{3, {0, 1, 16}}, words).error(),
            SequencerStatus::kBadPinMap);
}

TEST(Sequencer, PinMapChecks) {
  EXPECT_EQ(check_pin_map(kPins012), SequencerStatus::kOk);
  EXPECT_EQ(check_pin_map(LedPinMap{0, {}}), SequencerStatus::kBadPinMap);
  EXPECT_EQ(check_pin_map(LedPinMap{5, {0, 1, 2, 3}}), SequencerStatus::kBadPinMap);
  EXPECT_EQ(check_pin_map(LedPinMap{4, {15, 14, 13, 12}}), SequencerStatus::kOk);
}

TEST(Sequencer, SlotTimeForExposureRoundsDown) {
  EXPECT_EQ(slot_time_for_exposure(5200, 52), 100u);
  EXPECT_EQ(slot_time_for_exposure(5251, 52), 100u);
  EXPECT_EQ(slot_time_for_exposure(51, 52), 0u);
  EXPECT_EQ(slot_time_for_exposure(100, 0), 0u);
}

}  // namespace
}  // namespace flutterscan
