// Photo scenes: a photo's colour channels as the reflectance under the three
// LEDs, scaled into kPhotoBlack..kPhotoWhite, placed on the belt, turned.

#include "sim/photo_scene.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "imaging/frame_conversion.hpp"
#include "sim/colour_scene.hpp"
#include "sim/pixel_integration.hpp"

namespace flutterscan::sim {
namespace {

namespace fs = std::filesystem;

class PhotoSceneTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("photo_scene_test_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  /// A 12 x 8 photo: white, a pure red pixel at (1, 1), a mid-grey pixel
  /// (sRGB 188) at (10, 1), black bottom row.
  std::string write_photo() {
    cv::Mat bgr(8, 12, CV_8UC3, cv::Scalar(255, 255, 255));
    bgr.at<cv::Vec3b>(1, 1) = {0, 0, 255};
    bgr.at<cv::Vec3b>(1, 10) = {188, 188, 188};
    bgr.row(7).setTo(cv::Scalar(0, 0, 0));
    const std::string path = (dir_ / "photo.png").string();
    EXPECT_TRUE(cv::imwrite(path, bgr));
    return path;
  }

  SceneSpec photo_spec(const std::string& path, int width = 40, int height = 30) {
    SceneSpec spec;
    spec.kind = SceneKind::kPhoto;
    spec.content = path;
    spec.width = width;
    spec.height = height;
    return spec;
  }

  fs::path dir_;
};

double reflectance(double srgb_8bit) {
  return kPhotoBlack + (kPhotoWhite - kPhotoBlack) * imaging::srgb_to_linear(srgb_8bit / 255);
}

TEST_F(PhotoSceneTest, ChannelsAreTheBandsScaledIntoTheStatedRangeOnTheBelt) {
  const SceneSpec spec = photo_spec(write_photo());
  const auto bands = render_photo_bands(spec);
  ASSERT_TRUE(bands.ok()) << bands.error();
  ASSERT_EQ(bands.value().size(), 3u);
  const auto layout = photo_layout(spec);
  ASSERT_TRUE(layout.ok());
  EXPECT_FALSE(layout.value().grey);
  // Whole-pixel placement: the photo's top-left pixel is camera pixel (14, 11).
  EXPECT_EQ(layout.value().centre_x, 14 + 6);
  EXPECT_EQ(layout.value().centre_y, 11 + 4);
  const int x0 = 14, y0 = 11;
  const auto& [red, green, blue] = std::tie(bands.value()[0], bands.value()[1], bands.value()[2]);
  EXPECT_NEAR(red.at(x0 + 1, y0 + 1), kPhotoWhite, 1e-6);  // red print: white under red
  EXPECT_NEAR(green.at(x0 + 1, y0 + 1), kPhotoBlack, 1e-6);
  EXPECT_NEAR(blue.at(x0 + 1, y0 + 1), kPhotoBlack, 1e-6);
  for (const auto* band : {&red, &green, &blue}) {
    EXPECT_NEAR(band->at(x0 + 10, y0 + 1), reflectance(188), 1e-6);
    EXPECT_NEAR(band->at(x0, y0), kPhotoWhite, 1e-6);
    EXPECT_NEAR(band->at(x0 + 5, y0 + 7), kPhotoBlack, 1e-6);
    EXPECT_EQ(band->at(x0 - 1, y0), static_cast<float>(spec.belt));  // belt around it
    EXPECT_EQ(band->at(x0 + 12, y0 + 7), static_cast<float>(spec.belt));
    EXPECT_EQ(band->at(x0, y0 + 8), static_cast<float>(spec.belt));
  }
  // The grey view is the bands' fusion.
  const auto grey = render_scene(spec);
  ASSERT_TRUE(grey.ok());
  EXPECT_NEAR(grey.value().at(x0 + 1, y0 + 1), (kPhotoWhite + 2 * kPhotoBlack) / 3, 1e-6);
}

TEST_F(PhotoSceneTest, SupersampledRenderingBinsToThePhotoItself) {
  const SceneSpec spec = photo_spec(write_photo());
  const auto coarse = render_photo_bands(spec, 1);
  const auto fine = render_photo_bands(spec, 4);
  ASSERT_TRUE(coarse.ok() && fine.ok());
  for (int band = 0; band < 3; ++band) {
    const imaging::Plane binned = bin_pixels(fine.value()[band], 4);
    ASSERT_EQ(binned.width, spec.width);
    for (std::size_t i = 0; i < binned.pixels.size(); ++i)
      ASSERT_NEAR(binned.pixels[i], coarse.value()[band].pixels[i], 1e-6) << band << " " << i;
  }
}

TEST_F(PhotoSceneTest, AGreyPhotoGivesThreeEqualBands) {
  const std::string path = (dir_ / "grey.png").string();
  cv::Mat grey(6, 10, CV_8UC1, cv::Scalar(200));
  grey.at<std::uint8_t>(2, 3) = 20;
  ASSERT_TRUE(cv::imwrite(path, grey));
  const SceneSpec spec = photo_spec(path);
  const auto bands = render_photo_bands(spec);
  ASSERT_TRUE(bands.ok());
  EXPECT_TRUE(photo_layout(spec).value().grey);
  EXPECT_EQ(bands.value()[0].pixels, bands.value()[1].pixels);
  EXPECT_EQ(bands.value()[1].pixels, bands.value()[2].pixels);
}

TEST_F(PhotoSceneTest, ATurnOfNinetyDegreesIsAnticlockwiseOnTheImage) {
  SceneSpec spec = photo_spec(write_photo());
  spec.rotate_deg = 90;
  const auto layout = photo_layout(spec);
  ASSERT_TRUE(layout.ok());
  EXPECT_EQ(layout.value().box_width, 8);
  EXPECT_EQ(layout.value().box_height, 12);
  const auto bands = render_photo_bands(spec);
  ASSERT_TRUE(bands.ok()) << bands.error();
  const imaging::Plane& green = bands.value()[1];
  // Turned anticlockwise about (20, 15): the black bottom row becomes the right
  // column (x = 23), the top row the left column (x = 16), the red pixel (photo
  // (1, 1), top-left) goes to the bottom-left: camera (17, 19).
  EXPECT_NEAR(green.at(23, 15), kPhotoBlack, 1e-6);
  EXPECT_NEAR(green.at(16, 12), kPhotoWhite, 1e-6);
  EXPECT_NEAR(green.at(17, 19), kPhotoBlack, 1e-6);
  EXPECT_NEAR(bands.value()[0].at(17, 19), kPhotoWhite, 1e-6);
  EXPECT_EQ(green.at(15, 15), static_cast<float>(spec.belt));
  EXPECT_EQ(green.at(24, 15), static_cast<float>(spec.belt));
}

TEST_F(PhotoSceneTest, AnyTurnKeepsThePhotoOnTheBeltAndItsMeanNearlyUnchanged) {
  SceneSpec spec = photo_spec(write_photo(), 48, 48);
  const auto straight = render_photo_bands(spec, 4);
  ASSERT_TRUE(straight.ok());
  auto mean_above_belt = [&](const imaging::Plane& p) {
    double sum = 0;
    for (float v : p.pixels) sum += v - spec.belt;
    return sum / p.pixels.size();
  };
  for (const double deg : {17.0, -33.0, 45.0, 180.0}) {
    spec.rotate_deg = deg;
    const auto turned = render_photo_bands(spec, 4);
    ASSERT_TRUE(turned.ok()) << deg << ": " << turned.error();
    // The area of each reflectance is kept (to the fine grid's sampling).
    EXPECT_NEAR(mean_above_belt(turned.value()[0]), mean_above_belt(straight.value()[0]), 0.005)
        << deg;
    EXPECT_EQ(turned.value()[1].at(0, 0), static_cast<float>(spec.belt)) << deg;
  }
}

TEST_F(PhotoSceneTest, BadInputIsAnErrorNamingIt) {
  const auto missing = render_photo_bands(photo_spec((dir_ / "absent.png").string()));
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.error().find("absent.png"), std::string::npos) << missing.error();

  const std::string junk = (dir_ / "junk.png").string();
  std::ofstream(junk) << "not a picture";
  const auto bad = render_photo_bands(photo_spec(junk));
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().find("junk.png"), std::string::npos) << bad.error();

  SceneSpec spec = photo_spec(write_photo());
  spec.rotate_deg = std::nan("");
  EXPECT_FALSE(render_photo_bands(spec).ok());
  spec.rotate_deg = 400;
  EXPECT_FALSE(render_photo_bands(spec).ok());

  spec = photo_spec(write_photo(), 20, 20);  // 12 + 2 x 8 = 28 wide needed
  const auto small = render_photo_bands(spec);
  ASSERT_FALSE(small.ok());
  EXPECT_NE(small.error().find("28 x 24"), std::string::npos) << small.error();
  const auto size = photo_frame_size(spec);
  ASSERT_TRUE(size.ok());
  EXPECT_EQ(size.value(), std::make_pair(28, 24));
}

}  // namespace
}  // namespace flutterscan::sim
