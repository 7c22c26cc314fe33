#include "plot/heat_map.hpp"

#include <cairo.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>

namespace flutterscan::plot {
namespace {

HeatMap two_by_two() {
  HeatMap map;
  map.title = "winner";
  map.x_label = "light";
  map.y_label = "noise";
  map.columns = {"100", "1000"};
  map.rows = {"1", "10"};
  map.categories = {"coded", "strobe"};
  map.category = {0, 1, 1, -1};
  map.cell_text = {"+1.0", "-0.5", "", ""};
  return map;
}

std::string temporary_path(const char* name) {
  return (std::filesystem::temp_directory_path() / (std::to_string(::getpid()) + name)).string();
}

TEST(HeatMap, CellsTakeTheirCategoryColour) {
  const std::string path = temporary_path("-heat.png");
  ASSERT_EQ(write_png(two_by_two(), path, 800, 480), "");
  cairo_surface_t* image = cairo_image_surface_create_from_png(path.c_str());
  ASSERT_EQ(cairo_surface_status(image), CAIRO_STATUS_SUCCESS);
  EXPECT_EQ(cairo_image_surface_get_width(image), 800);
  const unsigned char* data = cairo_image_surface_get_data(image);
  const int stride = cairo_image_surface_get_stride(image);
  auto pixel = [&](int x, int y) {
    const auto* p = reinterpret_cast<const std::uint32_t*>(data + y * stride) + x;
    return *p & 0xFFFFFFu;
  };
  // Bottom-left cell (category 0) and top-right cell (empty: white) differ;
  // sample near their corners, away from the labels.
  const std::uint32_t bottom_left = pixel(80, 400);
  const std::uint32_t top_right = pixel(560, 120);
  EXPECT_NE(bottom_left, 0xFFFFFFu);
  EXPECT_EQ(top_right, 0xFFFFFFu);
  EXPECT_NE(bottom_left, pixel(560, 400));  // category 1 beside it
  cairo_surface_destroy(image);
  std::filesystem::remove(path);
}

TEST(HeatMap, MismatchedSizesAreRefusedAndNothingIsWritten) {
  HeatMap map = two_by_two();
  map.category.pop_back();
  const std::string path = temporary_path("-bad.png");
  const std::string error = write_png(map, path);
  EXPECT_NE(error.find(path), std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(path));
  map = two_by_two();
  map.category[0] = 5;
  EXPECT_NE(write_png(map, path).find("no category"), std::string::npos);
}

}  // namespace
}  // namespace flutterscan::plot
