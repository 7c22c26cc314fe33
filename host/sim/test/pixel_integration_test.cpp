// The simulator's continuous motion (sim/pixel_integration.hpp): a scene
// rendered finer than the pixels, blurred on the fine grid and binned, and
// the pixel model the deblurring assumes (imaging/motion_psf.hpp).

#include "sim/pixel_integration.hpp"

#include <gtest/gtest.h>

#include <random>

#include "imaging/capture_model.hpp"
#include "sim/forward_model.hpp"

namespace flutterscan::sim {
namespace {

imaging::CaptureModel triplet_capture(double blur_px) {
  imaging::CaptureModel m;
  m.code = LedCode::parse("4242221144411121214241142422112112214412414144224412", 3).value();
  m.blur_px = blur_px;
  m.led_electrons = imaging::budgeted_led_electrons(m.code, 3000, 3);
  m.crosstalk = {0.90, 0.08, 0.01, 0.10, 0.85, 0.12, 0.01, 0.07, 0.88};
  m.ambient_electrons = {30, 20, 10};
  return m;
}

/// Each pixel of `coarse` repeated k x k times.
imaging::Plane replicated(const imaging::Plane& coarse, int k) {
  imaging::Plane fine(coarse.width * k, coarse.height * k);
  for (int y = 0; y < fine.height; ++y)
    for (int x = 0; x < fine.width; ++x) fine.at(x, y) = coarse.at(x / k, y / k);
  return fine;
}

imaging::Plane random_scene(int width, int height, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> value(0.05f, 0.9f);
  imaging::Plane p(width, height);
  for (float& v : p.pixels) v = value(rng);
  return p;
}

TEST(PixelIntegration, BinningAveragesBlocks) {
  imaging::Plane fine(4, 2);
  fine.pixels = {1, 2, 3, 4, 5, 6, 7, 8};
  const auto coarse = bin_pixels(fine, 2);
  ASSERT_EQ(coarse.width, 2);
  ASSERT_EQ(coarse.height, 1);
  EXPECT_FLOAT_EQ(coarse.at(0, 0), 3.5f);
  EXPECT_FLOAT_EQ(coarse.at(1, 0), 5.5f);
}

// A scene constant over each pixel moving continuously is exactly what the
// box-aperture model describes: the fine simulation and the model agree for
// fractional blurs, speed changes and every direction.
TEST(PixelIntegration, APixelWiseConstantSceneFollowsTheBoxApertureModel) {
  const auto scene = random_scene(150, 150, 3);
  for (double blur : {52.0, 37.3, 11.6})
    for (double ratio : {1.0, 1.4})
      for (auto d : {imaging::Direction::kPlusX, imaging::Direction::kMinusY}) {
        auto m = triplet_capture(blur);
        m.speed_ratio = ratio;
        m.direction = d;
        const auto model = expected_electrons(scene, m, 1);
        const auto simulated = expected_electrons(replicated(scene, 4), m, 4);
        for (int c = 0; c < 3; ++c) {
          const auto& a = model.channels[static_cast<std::size_t>(c)].pixels;
          const auto& b = simulated.channels[static_cast<std::size_t>(c)].pixels;
          ASSERT_EQ(a.size(), b.size());
          for (std::size_t i = 0; i < a.size(); ++i)
            ASSERT_NEAR(a[i], b[i], 1e-3 * std::abs(a[i]) + 1e-3)
                << blur << " " << ratio << " channel " << c << " sample " << i;
        }
      }
}

// Depositing whole taps (the older model) is not what a continuously moving
// scene gives: the simulator tells the two apart.
TEST(PixelIntegration, TheTapGridModelMissesTheApertureSmoothing) {
  const auto scene = random_scene(160, 8, 4);
  auto m = triplet_capture(52);
  const auto simulated = expected_electrons(replicated(scene, 4), m, 4);
  m.pixel_model = imaging::PixelModel::kTapGrid;
  const auto grid = expected_electrons(scene, m, 1);
  double largest = 0, level = 0;
  for (std::size_t i = 0; i < grid.channels[1].pixels.size(); ++i) {
    largest = std::max(largest, static_cast<double>(std::abs(grid.channels[1].pixels[i] -
                                                             simulated.channels[1].pixels[i])));
    level = std::max(level, static_cast<double>(simulated.channels[1].pixels[i]));
  }
  EXPECT_GT(largest, 0.01 * level);
}

}  // namespace
}  // namespace flutterscan::sim
