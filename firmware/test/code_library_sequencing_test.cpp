// Every code of the host's library, uploaded over the protocol and played on
// the virtual clock: exact LED pattern, exact slot timing, all off after.
#include <gtest/gtest.h>

#include <bit>

#include "codes/library.hpp"
#include "sequence_check.hpp"
#include "test_rig.hpp"

namespace flutterscan::firmware::test {
namespace {

using proto::Status;

/// A board with its LEDs on scattered pins, so pin mapping is exercised too.
BoardConfig scattered_board() {
  BoardConfig board = test_board();
  board.pins = LedPinMap{3, {3, 7, 12, 0}};
  return board;
}

TEST(CodeLibrarySequencing, EveryLibraryCodeIsPlayedExactly) {
  ASSERT_FALSE(codes::code_library().empty());
  for (const std::uint32_t slot_us : {1u, 37u, 100u, 10'000u}) {
    for (const auto& entry : codes::code_library()) {
      SCOPED_TRACE(std::string(entry.name) + " at " + std::to_string(slot_us) + " us");
      Rig rig(scattered_board());
      ASSERT_EQ(rig.send(proto::Command::kSetGuard, permissive_guard()).status(), Status::kOk);
      const LedCode code = codes::to_code(entry);
      ASSERT_EQ(rig.upload(5, code), Status::kOk);
      ASSERT_EQ(rig.select(5), Status::kOk);
      ASSERT_EQ(rig.set_timing(slot_us), Status::kOk);
      ASSERT_EQ(rig.arm(), Status::kOk);
      rig.port.clear_led_transitions();
      const std::uint64_t exposure = static_cast<std::uint64_t>(code.length()) * slot_us;
      rig.port.inject_strobe(777, static_cast<std::uint32_t>(exposure + 10));
      rig.port.inject_strobe(777 + 3 * exposure, static_cast<std::uint32_t>(exposure + 10));
      rig.port.run_until(777 + 6 * exposure);
      const auto& log = rig.port.led_transitions();
      ASSERT_EQ(log.size(), 2u * (static_cast<std::size_t>(code.length()) + 1));
      EXPECT_TRUE(plays_code(log, 0, code, 777, slot_us));
      EXPECT_TRUE(plays_code(log, log.size() / 2, code, 777 + 3 * exposure, slot_us));
      // Only the mapped pins ever move.
      for (const auto& t : log) EXPECT_EQ(t.pin_levels & ~((1u << 3) | (1u << 7) | (1u << 12)), 0u);
      if (code.leds() == 3 && code.is_one_of_n()) {
        const auto words_per_exposure = static_cast<std::size_t>(code.length()) + 1;
        for (std::size_t i = 0; i < log.size(); ++i) {
          const bool all_off_word = i % words_per_exposure == words_per_exposure - 1;
          EXPECT_EQ(std::popcount(static_cast<unsigned>(log[i].led_mask)), all_off_word ? 0 : 1)
              << "write " << i;
        }
      }
      const auto events = rig.events();
      ASSERT_EQ(events.size(), 2u);
      EXPECT_EQ(events[1].start_time_us, 777 + 3 * exposure);
      EXPECT_EQ(events[1].slot_count, code.length());
      EXPECT_EQ(events[1].slot_time_us, slot_us);
    }
  }
}

TEST(CodeLibrarySequencing, SeedTripletsAreUploadedAsOneOfThree) {
  Rig rig;
  int triplets = 0;
  for (const auto& entry : codes::code_library()) {
    if (!entry.seed_triplet) continue;
    ++triplets;
    EXPECT_EQ(rig.upload(0, codes::to_code(entry), proto::kCodeFlagOneOfN), Status::kOk)
        << entry.name;
  }
  EXPECT_GE(triplets, 3);
}

TEST(CodeLibrarySequencing, LongestCodeTakesSeveralChunks) {
  std::string digits;
  for (int i = 0; i < kMaxSlots; ++i) digits += "1247"[i % 4];
  const LedCode code = LedCode::parse(digits, 3).value();
  Rig rig;
  ASSERT_EQ(rig.send(proto::Command::kSetGuard, permissive_guard()).status(), Status::kOk);
  ASSERT_EQ(rig.upload(7, code), Status::kOk);
  ASSERT_EQ(rig.select(7), Status::kOk);
  ASSERT_EQ(rig.set_timing(3), Status::kOk);
  ASSERT_EQ(rig.arm(), Status::kOk);
  rig.port.clear_led_transitions();
  rig.port.inject_strobe(100, 1'000);
  rig.port.run_until(2'000);
  EXPECT_TRUE(plays_code(rig.port.led_transitions(), 0, code, 100, 3));
}

}  // namespace
}  // namespace flutterscan::firmware::test
