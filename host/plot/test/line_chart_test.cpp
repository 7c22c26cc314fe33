#include "plot/line_chart.hpp"

#include <cairo.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <string>

namespace flutterscan::plot {
namespace {

namespace fs = std::filesystem;

constexpr int kWidth = 640;
constexpr int kHeight = 400;
constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

/// A PNG read back with Cairo.
class Image {
 public:
  explicit Image(const fs::path& path)
      : surface_(cairo_image_surface_create_from_png(path.c_str()), cairo_surface_destroy) {}

  bool ok() const { return cairo_surface_status(surface_.get()) == CAIRO_STATUS_SUCCESS; }
  int width() const { return cairo_image_surface_get_width(surface_.get()); }
  int height() const { return cairo_image_surface_get_height(surface_.get()); }

  /// Pixels in columns x0..x1-1 and rows y0..y1-1 that are nearly pure red.
  int red_pixels(int x0, int y0, int x1, int y1) const {
    const unsigned char* data = cairo_image_surface_get_data(surface_.get());
    const int stride = cairo_image_surface_get_stride(surface_.get());
    int count = 0;
    for (int y = y0; y < y1; ++y) {
      const auto* row = reinterpret_cast<const std::uint32_t*>(data + y * stride);
      for (int x = x0; x < x1; ++x) {
        const std::uint32_t pixel = row[x];
        const unsigned r = (pixel >> 16) & 0xff;
        const unsigned g = (pixel >> 8) & 0xff;
        const unsigned b = pixel & 0xff;
        if (r >= 200 && g <= 60 && b <= 60) ++count;
      }
    }
    return count;
  }

 private:
  std::unique_ptr<cairo_surface_t, decltype(&cairo_surface_destroy)> surface_;
};

Series red_series(std::vector<double> x, std::vector<double> y) {
  Series series;
  series.x = std::move(x);
  series.y = std::move(y);
  series.colour = {1, 0, 0};
  series.line_width = 3;
  return series;
}

/// A chart of `series` over 0..1 x 0..1, so y = 0.5 runs through the middle of the image.
LineChart unit_chart(Series series) {
  LineChart chart;
  chart.title = "Test chart";
  chart.x_label = "x";
  chart.y_label = "y";
  chart.x_min = 0;
  chart.x_max = 1;
  chart.y_min = 0;
  chart.y_max = 1;
  chart.series.push_back(std::move(series));
  return chart;
}

std::vector<double> steps(int count, double step) {
  std::vector<double> values;
  for (int i = 0; i < count; ++i) values.push_back(i * step);
  return values;
}

class LineChartTest : public testing::Test {
 protected:
  void SetUp() override {
    const auto* info = testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("plot_test_" + std::to_string(::getpid()) + "_" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  fs::path dir_;
};

TEST_F(LineChartTest, WritesPngOfRequestedSize) {
  const fs::path path = dir_ / "chart.png";
  ASSERT_EQ(write_png(unit_chart(red_series({0, 1}, {0.2, 0.8})), path, kWidth, kHeight), "");
  const Image image(path);
  ASSERT_TRUE(image.ok());
  EXPECT_EQ(image.width(), kWidth);
  EXPECT_EQ(image.height(), kHeight);
}

TEST_F(LineChartTest, RedSeriesIsDrawnInsideThePlotAreaOnly) {
  const fs::path path = dir_ / "chart.png";
  ASSERT_EQ(write_png(unit_chart(red_series(steps(11, 0.1), std::vector(11, 0.5))), path, kWidth,
                      kHeight),
            "");
  const Image image(path);
  ASSERT_TRUE(image.ok());
  EXPECT_GT(image.red_pixels(kWidth / 4, kHeight / 4, 3 * kWidth / 4, 3 * kHeight / 4), 100);
  EXPECT_EQ(image.red_pixels(0, 0, kWidth / 8, kHeight / 8), 0);
}

TEST_F(LineChartTest, ClipsCurvesLeavingTheRange) {
  const fs::path path = dir_ / "chart.png";
  const std::vector<double> y = {0.5, 1e6, 0.5, -1e6, 0.5, 1e300, 0.5, -1e300, 0.5, 3, 0.5};
  ASSERT_EQ(write_png(unit_chart(red_series(steps(11, 0.1), y)), path, kWidth, kHeight), "");
  const Image image(path);
  ASSERT_TRUE(image.ok());
  EXPECT_GT(image.red_pixels(0, 0, kWidth, kHeight), 100);
  const int border = kHeight / 50;
  EXPECT_EQ(image.red_pixels(0, 0, kWidth, border), 0);
  EXPECT_EQ(image.red_pixels(0, kHeight - border, kWidth, kHeight), 0);
  EXPECT_EQ(image.red_pixels(0, 0, border, kHeight), 0);
  EXPECT_EQ(image.red_pixels(kWidth - border, 0, kWidth, kHeight), 0);
}

TEST_F(LineChartTest, NanBreaksTheLine) {
  const fs::path path = dir_ / "chart.png";
  std::vector<double> y(11, 0.5);
  y[5] = kNan;
  ASSERT_EQ(write_png(unit_chart(red_series(steps(11, 0.1), y)), path, kWidth, kHeight), "");
  const Image image(path);
  ASSERT_TRUE(image.ok());
  // The line runs from x = 0 to 1 with a gap over 0.4..0.6 around the middle column.
  int left = kWidth;
  int right = -1;
  for (int x = 0; x < kWidth; ++x) {
    if (image.red_pixels(x, kHeight / 4, x + 1, 3 * kHeight / 4) > 0) {
      left = std::min(left, x);
      right = std::max(right, x);
    }
  }
  ASSERT_LT(left, right);
  const int middle = (left + right) / 2;
  EXPECT_EQ(image.red_pixels(middle - 5, 0, middle + 5, kHeight), 0);
  EXPECT_GT(image.red_pixels(left + (right - left) / 4, 0, left + (right - left) / 4 + 1, kHeight),
            0);
}

TEST_F(LineChartTest, InfiniteValuesRender) {
  const fs::path path = dir_ / "chart.png";
  LineChart chart;
  chart.series.push_back(red_series({0, 1, 2, 3, kInf}, {1, -kInf, 3, kInf, 5}));
  ASSERT_EQ(write_png(chart, path, kWidth, kHeight), "");
  EXPECT_TRUE(Image(path).ok());
}

TEST_F(LineChartTest, DeepNullDoesNotStretchTheAutoscale) {
  // Markers from 0 down to -29.5 with one -240 null: fitted to about -30..0 the markers
  // fill the plot's height; stretched to -240 they would all sit in its top sixth.
  const fs::path path = dir_ / "chart.png";
  std::vector<double> x = steps(60, 1);
  std::vector<double> y = steps(60, -0.5);
  x.push_back(30.5);
  y.push_back(-240);
  Series series = red_series(x, y);
  series.line_width = 0;
  series.marker_radius = 4;
  LineChart chart;
  chart.series.push_back(series);
  ASSERT_EQ(write_png(chart, path, kWidth, kHeight), "");
  const Image image(path);
  ASSERT_TRUE(image.ok());
  EXPECT_GT(image.red_pixels(0, kHeight / 2, kWidth, 3 * kHeight / 4), 50);
}

TEST_F(LineChartTest, LogXSkipsNonPositiveValues) {
  const fs::path path = dir_ / "chart.png";
  LineChart chart;
  chart.log_x = true;
  chart.series.push_back(red_series({-1, 0, 1, 10, 100, 1000}, {5, 4, 3, 2, 1, 0}));
  ASSERT_EQ(write_png(chart, path, kWidth, kHeight), "");
  const Image image(path);
  ASSERT_TRUE(image.ok());
  EXPECT_GT(image.red_pixels(0, 0, kWidth, kHeight), 100);
}

TEST_F(LineChartTest, EmptyChartIsAnError) {
  const fs::path path = dir_ / "chart.png";
  EXPECT_NE(write_png(LineChart{}, path, kWidth, kHeight), "");
  EXPECT_FALSE(fs::exists(path));
}

TEST_F(LineChartTest, MismatchedLengthsAreAnErrorAndWriteNothing) {
  const fs::path path = dir_ / "chart.png";
  const std::string error = write_png(unit_chart(red_series({0, 1, 2}, {0, 1})), path);
  EXPECT_NE(error, "");
  EXPECT_NE(error.find("y values"), std::string::npos) << error;
  EXPECT_TRUE(fs::is_empty(dir_));
}

TEST_F(LineChartTest, MissingDirectoryIsAnErrorNamingThePath) {
  const fs::path path = dir_ / "missing" / "chart.png";
  const std::string error = write_png(unit_chart(red_series({0, 1}, {0, 1})), path);
  EXPECT_NE(error.find(path.string()), std::string::npos) << error;
  EXPECT_TRUE(fs::is_empty(dir_));
}

TEST_F(LineChartTest, ReplacesAnExistingFileWholly) {
  const fs::path path = dir_ / "chart.png";
  {
    std::ofstream old(path, std::ios::binary);
    old << std::string(4 << 20, 'x');
  }
  ASSERT_EQ(write_png(unit_chart(red_series({0, 1}, {0, 1})), path, kWidth, kHeight), "");
  EXPECT_LT(fs::file_size(path), 1u << 20);
  const Image image(path);
  ASSERT_TRUE(image.ok());
  EXPECT_EQ(image.width(), kWidth);
  int files = 0;
  for ([[maybe_unused]] const auto& entry : fs::directory_iterator(dir_)) ++files;
  EXPECT_EQ(files, 1) << "temporary files left behind";
}

}  // namespace
}  // namespace flutterscan::plot
