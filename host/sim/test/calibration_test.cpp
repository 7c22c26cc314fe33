// The calibrations recover the simulator's true values: the crosstalk matrix,
// black levels and LED strengths from one frame per LED; gain and read noise
// from a photon transfer series.

#include <gtest/gtest.h>

#include <cmath>

#include "imaging/crosstalk_calibration.hpp"
#include "imaging/photon_transfer.hpp"
#include "imaging/test/label_capture.hpp"
#include "sim/forward_model.hpp"

namespace flutterscan::sim {
namespace {

using imaging::CaptureModel;

const std::vector<double> kCrosstalk = test_fixtures::reference_camera().crosstalk;

/// A static white target (blur well under a pixel) under `code`, 12 bits, 64 DN black.
CaptureModel white_target(const char* code, double electrons,
                          const std::vector<double>& crosstalk = kCrosstalk) {
  CaptureModel m = test_fixtures::reference_camera(64);
  m.code = LedCode::parse(code, 3).value();
  m.blur_px = 0.01;
  m.crosstalk = crosstalk;
  m.led_electrons = {electrons / 52, electrons / 52, electrons / 52};
  return m;
}

imaging::Image frame_of(const CaptureModel& m, std::uint64_t seed, int size = 200) {
  const imaging::Plane white(size, size, 1.0f);
  return record_frame(expected_electrons(white, m), m, seed);
}

std::string repeat(char digit) {
  return std::string(52, digit);
}

TEST(CrosstalkCalibration, RecoversTheMatrixBlackLevelsAndStrengths) {
  const std::vector<double> strengths = {3000, 2400, 2000};  // e- per exposure, per LED
  std::vector<imaging::Image> lit;
  for (int k = 0; k < 3; ++k) {
    CaptureModel m = white_target(repeat(static_cast<char>('0' + (1 << k))).c_str(), 0);
    m.led_electrons = {0, 0, 0};
    m.led_electrons[static_cast<std::size_t>(k)] = strengths[static_cast<std::size_t>(k)] / 52;
    lit.push_back(frame_of(m, 10 + static_cast<std::uint64_t>(k)));
  }
  CaptureModel off = white_target(repeat('0').c_str(), 0);
  const auto result = imaging::calibrate_crosstalk(frame_of(off, 1), lit, 4095);
  ASSERT_TRUE(result.ok()) << result.error();
  const auto& cal = result.value();
  for (int k = 0; k < 3; ++k) {
    double column = 0;
    for (int c = 0; c < 3; ++c) column += kCrosstalk[static_cast<std::size_t>(c * 3 + k)];
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(cal.crosstalk[static_cast<std::size_t>(c * 3 + k)],
                  kCrosstalk[static_cast<std::size_t>(c * 3 + k)] / column, 0.003)
          << "M[" << c << "][" << k << "]";
    const double expected_dn = strengths[static_cast<std::size_t>(k)] * column / (12000.0 / 4095.0);
    EXPECT_NEAR(cal.led_strength_dn[static_cast<std::size_t>(k)], expected_dn, 0.01 * expected_dn);
  }
  for (double black : cal.black_level_dn) EXPECT_NEAR(black, 64, 0.5);
  EXPECT_LT(cal.condition_number, 2.0);
  EXPECT_TRUE(cal.warning.empty());
}

TEST(CrosstalkCalibration, WarnsWhenTheLedsBarelySeparate) {
  const std::vector<double> overlapping = {0.50, 0.46, 0.0, 0.50, 0.54, 0.0, 0.0, 0.0, 1.0};
  std::vector<imaging::Image> lit;
  for (int k = 0; k < 3; ++k)
    lit.push_back(frame_of(
        white_target(repeat(static_cast<char>('0' + (1 << k))).c_str(), 3000, overlapping), 20));
  const auto result =
      imaging::calibrate_crosstalk(frame_of(white_target(repeat('0').c_str(), 0), 2), lit, 4095);
  ASSERT_TRUE(result.ok()) << result.error();
  EXPECT_GT(result.value().condition_number, imaging::kPoorSeparationCondition);
  EXPECT_NE(result.value().warning.find("condition number"), std::string::npos);
}

TEST(CrosstalkCalibration, RefusesUnusableFrames) {
  const auto dark = frame_of(white_target(repeat('0').c_str(), 0), 3);
  std::vector<imaging::Image> lit = {frame_of(white_target(repeat('1').c_str(), 3000), 4),
                                     dark};  // LED 1 never lit
  const auto unlit = imaging::calibrate_crosstalk(dark, lit, 4095);
  ASSERT_FALSE(unlit.ok());
  EXPECT_NE(unlit.error().find("LED 1"), std::string::npos) << unlit.error();
  std::vector<imaging::Image> saturated = {frame_of(white_target(repeat('1').c_str(), 40000), 5)};
  const auto clipped = imaging::calibrate_crosstalk(dark, saturated, 4095);
  ASSERT_FALSE(clipped.ok());
  EXPECT_NE(clipped.error().find("saturates"), std::string::npos) << clipped.error();
  std::vector<imaging::Image> small = {frame_of(white_target(repeat('1').c_str(), 3000), 6, 100)};
  EXPECT_FALSE(imaging::calibrate_crosstalk(dark, small, 4095).ok());
}

TEST(ConditionNumber, OfKnownMatrices) {
  EXPECT_NEAR(imaging::condition_number({1, 0, 0, 0, 1, 0, 0, 0, 1}, 3, 3), 1.0, 1e-9);
  EXPECT_NEAR(imaging::condition_number({2, 0, 0, 0.1}, 2, 2), 20.0, 1e-9);
  EXPECT_NEAR(imaging::condition_number({1, 1, 0, 1}, 2, 2), (3 + std::sqrt(5.0)) / 2, 1e-9);
  EXPECT_TRUE(std::isinf(imaging::condition_number({1, 2, 2, 4}, 2, 2)));
}

TEST(PhotonTransfer, RecoversGainAndReadNoise) {
  const double gain = 12000.0 / 4095.0;
  auto pair_at = [&](double electrons, std::uint64_t seed) {
    const CaptureModel m =
        white_target(repeat('7').c_str(), electrons, {1, 0, 0, 0, 1, 0, 0, 0, 1});
    return imaging::FlatPair{frame_of(m, seed, 256), frame_of(m, seed + 1, 256)};
  };
  const imaging::FlatPair dark = pair_at(0, 100);
  std::vector<imaging::FlatPair> flats;
  std::uint64_t seed = 200;
  for (double e : {300.0, 1000.0, 3000.0, 6000.0, 8000.0, 11500.0})
    flats.push_back(pair_at(e, seed += 2));
  const auto result = imaging::photon_transfer(dark, flats, 4095);
  ASSERT_TRUE(result.ok()) << result.error();
  for (int c = 0; c < 3; ++c) {
    const auto ci = static_cast<std::size_t>(c);
    EXPECT_NEAR(result.value().gain_e_per_dn[ci], gain, 0.03 * gain) << c;
    EXPECT_NEAR(result.value().read_noise_e[ci], 4.0, 0.4) << c;
    EXPECT_NEAR(result.value().black_level_dn[ci], 64, 0.5) << c;
    EXPECT_FALSE(result.value().points[ci].back().fitted);  // past 70% of saturation
  }
}

TEST(PhotonTransfer, NeedsTwoLevelsInRange) {
  auto pair_at = [&](double electrons, std::uint64_t seed) {
    const CaptureModel m = white_target(repeat('7').c_str(), electrons);
    return imaging::FlatPair{frame_of(m, seed, 64), frame_of(m, seed + 1, 64)};
  };
  std::vector<imaging::FlatPair> one = {pair_at(3000, 2)};
  const auto result = imaging::photon_transfer(pair_at(0, 0), one, 4095);
  ASSERT_FALSE(result.ok());
  EXPECT_NE(result.error().find("two or more levels"), std::string::npos) << result.error();
}

}  // namespace
}  // namespace flutterscan::sim
