#include "codes/incremental_spectra.hpp"

#include <gtest/gtest.h>

#include <random>

#include "codes/search.hpp"

namespace flutterscan::codes {
namespace {

TEST(IncrementalSpectra, FollowsSlotChangesExactlyLikeAFreshFft) {
  auto code = LedCode::parse("2212441414112412441224111241244244242212442211444144", 3).value();
  const MeritSettings settings;
  IncrementalSpectra state(code, merit_grid(Merit::kJoint, 52, settings, search_grid_points(52)));
  std::mt19937 rng(3);
  for (int step = 0; step < 5000; ++step) {
    const int slot = static_cast<int>(rng() % 52);
    const auto mask = static_cast<std::uint8_t>(1U << (rng() % 3));
    state.set_mask(slot, mask);
    code.set_mask(slot, mask);
  }
  EXPECT_EQ(state.code(), code);
  const GridSpectra fresh = grid_spectra(Merit::kJoint, code, settings, search_grid_points(52));
  ASSERT_EQ(fresh.h.size(), state.spectra().h.size());
  for (std::size_t i = 0; i < fresh.h.size(); ++i)
    EXPECT_NEAR(std::abs(fresh.h[i] - state.spectra().h[i]), 0.0, 1e-9) << i;
  for (int k = 0; k < 3; ++k) EXPECT_EQ(state.spectra().on_slots[k], code.on_slots(k));
  EXPECT_NEAR(merit_on_grid(Merit::kJoint, state.spectra(), settings),
              merit_on_grid(Merit::kJoint, fresh, settings), 1e-9);
}

TEST(IncrementalSpectra, AssignReplacesTheCode) {
  const auto a = LedCode::parse("1111", 1).value();
  const auto b = LedCode::parse("1000", 1).value();
  const MeritSettings settings;
  IncrementalSpectra state(a, merit_grid(Merit::kMaxMin, 4, settings, 0));
  state.assign(b);
  EXPECT_EQ(state.spectra().on_slots[0], 1);
  for (const auto& value : state.spectra().led(0)) EXPECT_NEAR(std::abs(value), 1.0, 1e-12);
}

}  // namespace
}  // namespace flutterscan::codes
