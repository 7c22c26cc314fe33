#include "codes/spectrum.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace flutterscan::codes {
namespace {

constexpr std::string_view kRaskar = "1010000111000001010000110011110111010111001001100111";

std::vector<double> raskar() {
  return led_sequence(LedCode::parse(kRaskar, 1).value(), 0);
}

double min_of(const SampledSpectrum& s) {
  return *std::min_element(s.db.begin(), s.db.end());
}

TEST(Spectrum, SeedGridIsFirstPowerOfTwoAbove) {
  EXPECT_EQ(seed_grid_size(52), 64);
  EXPECT_EQ(seed_grid_size(64), 128);
  EXPECT_EQ(seed_grid_size(1), 2);
}

TEST(Spectrum, SeedGridHasBinsZeroToHalf) {
  const auto grid = seed_grid_spectrum(raskar());
  ASSERT_EQ(grid.db.size(), 33u);
  EXPECT_DOUBLE_EQ(grid.frequency[32], 0.5);
  // DC: 26 ones, 20 log10(26 / 32).
  EXPECT_NEAR(grid.db[0], 20 * std::log10(26.0 / 32.0), 1e-12);
}

TEST(Spectrum, FftAgreesWithDirectDtft) {
  const auto sequence = raskar();
  const auto bins = padded_dft(sequence, 64);
  for (int j = 0; j <= 32; ++j)
    EXPECT_NEAR(std::abs(bins[static_cast<std::size_t>(j)] - dtft(sequence, j / 64.0)), 0.0, 1e-9);
}

TEST(Spectrum, DenseGridRevealsDeeperMinimumThanSeedGrid) {
  // docs/codes.md: Raskar's code is -25.44 dB on the 64-point grid and -27.7 dB on a dense grid.
  const auto sequence = raskar();
  EXPECT_NEAR(min_of(seed_grid_spectrum(sequence)), -25.4359, 5e-5);
  const Minimum dense = dense_minimum_db(sequence);
  EXPECT_NEAR(dense.refined_value, -27.67, 0.01);
  EXPECT_LE(dense.refined_value, dense.grid_value);
  EXPECT_NEAR(dense.refined_frequency, 0.418, 0.001);
}

TEST(Spectrum, RefinementBeatsTheGrid) {
  // A smooth function with its minimum between grid points.
  const std::vector<double> samples = [] {
    std::vector<double> s(11);
    for (int j = 0; j <= 10; ++j) s[static_cast<std::size_t>(j)] = std::pow(0.05 * j - 0.1234, 2);
    return s;
  }();
  const Minimum m =
      minimise_over_frequency(samples, [](double f) { return std::pow(f - 0.1234, 2); });
  EXPECT_NEAR(m.grid_frequency, 0.1, 1e-12);
  EXPECT_NEAR(m.refined_frequency, 0.1234, 1e-6);
  EXPECT_LT(m.refined_value, 1e-10);
}

TEST(Spectrum, ComplementsShareTheCircularSpectrumButNotTheLinearOne) {
  const auto code = LedCode::parse(kRaskar, 1).value();
  const auto a = led_sequence(code, 0);
  const auto b = led_sequence(code.complement(), 0);
  const auto ca = circular_spectrum(a);
  const auto cb = circular_spectrum(b);
  ASSERT_EQ(ca.db.size(), 27u);
  for (std::size_t j = 1; j < ca.db.size(); ++j) EXPECT_NEAR(ca.db[j], cb.db[j], 1e-9) << j;
  // Under linear blur (zero padding) the complement is a different spectrum.
  const auto la = dense_spectrum(a, 1024);
  const auto lb = dense_spectrum(b, 1024);
  double largest_gap = 0;
  for (std::size_t j = 1; j < la.db.size(); ++j)
    largest_gap = std::max(largest_gap, std::abs(la.db[j] - lb.db[j]));
  EXPECT_GT(largest_gap, 10.0);
  EXPECT_GT(std::abs(dense_minimum_db(a).refined_value - dense_minimum_db(b).refined_value), 0.5);
}

TEST(Spectrum, ExactNullMapsToTheNullFloor) {
  // Alternating sum zero: a null at f = 0.5.
  const std::vector<double> sequence = {1, 1, 0, 0};
  const auto grid = seed_grid_spectrum(sequence);
  EXPECT_EQ(grid.db.back(), kNullDb);
  EXPECT_EQ(seed_db(0.0, 4), kNullDb);
  EXPECT_GE(seed_db(1e-11, 52), kNullDb);
}

}  // namespace
}  // namespace flutterscan::codes
