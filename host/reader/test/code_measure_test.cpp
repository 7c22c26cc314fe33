// The read record's measurements against the simulator's ground truth: a
// scene knows where its symbol lies and how big its modules are
// (sim::symbol_placement), so corners, module size, symbology identifier and
// the indicative grade are checked on images whose truth is known.
#include "reader/code_measure.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>

#include "reader/barcode_reader.hpp"
#include "sim/scene.hpp"

namespace flutterscan::reader {
namespace {

struct Rendered {
  imaging::Plane image;
  sim::SymbolPlacement truth;
};

Rendered render(const std::string& scene, double module_px, double ink = 0.06, double noise = 0) {
  auto spec = sim::parse_scene(scene);
  EXPECT_TRUE(spec.ok()) << scene;
  spec.value().width = 640;
  spec.value().height = 400;
  spec.value().module_px = module_px;
  spec.value().ink = ink;
  auto image = sim::render_scene(spec.value());
  EXPECT_TRUE(image.ok()) << image.error();
  auto truth = sim::symbol_placement(spec.value());
  EXPECT_TRUE(truth.ok()) << truth.error();
  std::mt19937_64 rng(7);
  std::normal_distribution<float> normal(0.0f, static_cast<float>(noise));
  if (noise > 0)
    for (float& v : image.value().pixels) v = std::clamp(v + normal(rng), 0.0f, 1.0f);
  return {std::move(image.value()), truth.value()};
}

/// The one code read on `image`, with its measurements.
DecodedCode read_one(const imaging::Plane& image) {
  const BarcodeReadout readout = read_barcodes(image);
  EXPECT_EQ(readout.codes.size(), 1u);
  return readout.codes.empty() ? DecodedCode{} : readout.codes.front();
}

double corner_error(const CodeCorners& found, const sim::SymbolPlacement& truth) {
  double worst = 0;
  for (int i = 0; i < 4; ++i)
    worst = std::max({worst, std::abs(found[i].x - truth.corners[i][0]),
                      std::abs(found[i].y - truth.corners[i][1])});
  return worst;
}

class LinearCodes : public ::testing::TestWithParam<std::pair<std::string, double>> {};

TEST_P(LinearCodes, CornersModuleSizeAndIdentifierMatchTheSceneAndTheGradeIsA) {
  const auto& [scene, module_px] = GetParam();
  const Rendered r = render(scene, module_px);
  const DecodedCode code = read_one(r.image);
  ASSERT_TRUE(code.quality.measured) << code.quality.problem;
  EXPECT_EQ(code.symbology_id, r.truth.symbology_id);
  EXPECT_LT(corner_error(code.quality.corners, r.truth), 1.0) << scene;
  EXPECT_EQ(code.quality.modules, r.truth.modules) << scene;
  EXPECT_NEAR(code.quality.module_px, module_px, 0.02 * module_px) << scene;
  // Two-tone print, 0.9 paper and 0.06 ink: every ISO parameter at its best.
  EXPECT_NEAR(code.quality.symbol_contrast, 0.84, 0.02);
  EXPECT_EQ(code.quality.grade, 'A') << code.quality.grade_value;
  EXPECT_EQ(code.quality.scans, 10);
}

INSTANTIATE_TEST_SUITE_P(Scenes, LinearCodes,
                         ::testing::Values(std::pair<std::string, double>{"code128:FS-00042", 2.5},
                                           std::pair<std::string, double>{"code128:LINE-7", 3.0},
                                           std::pair<std::string, double>{"ean13:590123412345",
                                                                          2.0}));

class MatrixCodes : public ::testing::TestWithParam<std::pair<std::string, double>> {};

TEST_P(MatrixCodes, CornersWithin2PxAndModuleSizeWithin10Percent) {
  const auto& [scene, module_px] = GetParam();
  const Rendered r = render(scene, module_px);
  const DecodedCode code = read_one(r.image);
  ASSERT_TRUE(code.quality.measured) << code.quality.problem;
  EXPECT_EQ(code.symbology_id, r.truth.symbology_id);
  EXPECT_LT(corner_error(code.quality.corners, r.truth), 2.0) << scene;
  EXPECT_EQ(code.quality.modules, r.truth.modules) << scene;
  EXPECT_NEAR(code.quality.module_px, module_px, 0.1 * module_px) << scene;
  EXPECT_EQ(code.quality.grade, 'A') << code.quality.grade_value;
}

INSTANTIATE_TEST_SUITE_P(
    Scenes, MatrixCodes,
    ::testing::Values(std::pair<std::string, double>{"qr:FS-QR-0042", 4.0},
                      std::pair<std::string, double>{"datamatrix:FS-DM-42", 4.0},
                      std::pair<std::string, double>{"qr:https://example.com/fs", 3.0}));

TEST(CodeMeasure, TheGradeFallsWithThePrintContrastAndNeverRises) {
  double previous = 5;
  char lowest = 'A', highest = 'F';
  for (double contrast = 0.9; contrast > 0.15; contrast -= 0.1) {
    const Rendered r = render("code128:FS-GRADE", 3.0, 0.9 - contrast, 0.02);
    const BarcodeReadout readout = read_barcodes(r.image);
    if (readout.codes.empty()) break;  // too faint to read at all: lower still is F
    const CodeQuality& q = readout.codes.front().quality;
    ASSERT_TRUE(q.measured) << q.problem;
    EXPECT_NEAR(q.symbol_contrast, contrast, 0.1) << contrast;
    EXPECT_LE(q.grade_value, previous + 1e-9) << "at print contrast " << contrast;
    previous = q.grade_value;
    lowest = std::max(lowest, q.grade);
    highest = std::min(highest, q.grade);
  }
  EXPECT_EQ(highest, 'A');
  EXPECT_GE(lowest, 'D');  // letters: 'D' and 'F' sort after 'A'
}

TEST(CodeMeasure, ACodeTurnedBy90DegreesHasItsCornersTurnedToo) {
  const Rendered r = render("code128:FS-TURN", 3.0);
  imaging::Plane turned(r.image.height, r.image.width);
  for (int y = 0; y < r.image.height; ++y)
    for (int x = 0; x < r.image.width; ++x) turned.at(y, x) = r.image.at(x, y);
  const DecodedCode code = read_one(turned);
  ASSERT_TRUE(code.quality.measured) << code.quality.problem;
  EXPECT_NEAR(code.quality.module_px, 3.0, 0.06);
  // The symbol's box, transposed.
  double min_x = 1e9, max_x = -1e9, min_y = 1e9, max_y = -1e9;
  for (const CodePoint& c : code.quality.corners) {
    min_x = std::min(min_x, c.x), max_x = std::max(max_x, c.x);
    min_y = std::min(min_y, c.y), max_y = std::max(max_y, c.y);
  }
  EXPECT_NEAR(min_x, r.truth.corners[0][1], 1.0);
  EXPECT_NEAR(max_x, r.truth.corners[2][1], 1.0);
  EXPECT_NEAR(min_y, r.truth.corners[0][0], 1.0);
  EXPECT_NEAR(max_y, r.truth.corners[2][0], 1.0);
}

/// The scene's symbol corners, as the reader gives them.
CodeCorners truth_corners(const Rendered& r) {
  CodeCorners corners{};
  for (int i = 0; i < 4; ++i) corners[i] = {r.truth.corners[i][0], r.truth.corners[i][1]};
  return corners;
}

/// Paper texture or noise on the line the reader decoded on: every dark run of
/// 4 px or more along the symbol's middle row gets a 1 px bright gap over the
/// `half_rows` rows either side of it. Returns the gaps made.
int split_wide_bars(imaging::Plane& image, const CodeCorners& corners, int half_rows) {
  const int middle = static_cast<int>(std::lround(0.5 * (corners[0].y + corners[3].y)));
  const int x0 = static_cast<int>(corners[0].x), x1 = static_cast<int>(corners[1].x);
  int gaps = 0;
  for (int x = x0; x < x1;) {
    int end = x;
    while (end < x1 && image.at(end, middle) < 0.5f) ++end;
    if (end - x >= 4) {
      for (int y = middle - half_rows; y <= middle + half_rows; ++y)
        image.at((x + end) / 2, y) = 0.9f;
      ++gaps;
    }
    x = std::max(end, x + 1);
  }
  return gaps;
}

/// A linear code whose centre line's wide bars are split: the scene, its
/// format, module px and the rows split either side of the middle one.
struct SplitBars {
  std::string scene, format;
  double module_px = 0;
  int half_rows = 0;
};

class SplitLinearCodes : public ::testing::TestWithParam<SplitBars> {};

// The count of elements on the centre line is no symbol's. EAN-13 (split over
// five rows) has one length: 95 modules over the symbol's extent. Code 128
// (split over three rows, as a fleck of paper texture would) has none: its
// modules follow from its count of bars and spaces (11 per character and 13),
// which the lines 4 px either side, averaged along the bars, give back.
TEST_P(SplitLinearCodes, TheModulesAreTheSymbolsWhateverTheCentreLineCounts) {
  const SplitBars& c = GetParam();
  Rendered r = render(c.scene, c.module_px);
  const CodeCorners corners = truth_corners(r);
  ASSERT_GE(split_wide_bars(r.image, corners, c.half_rows), 5);
  const CodeQuality q = measure_code(r.image, c.format, corners);
  ASSERT_TRUE(q.measured) << q.problem;
  EXPECT_EQ(q.modules, r.truth.modules) << c.scene;
  EXPECT_NEAR(q.module_px, c.module_px, 0.02 * c.module_px) << c.scene;
}

INSTANTIATE_TEST_SUITE_P(Scenes, SplitLinearCodes,
                         ::testing::Values(SplitBars{"ean13:590123412345", "EAN-13", 2.0, 2},
                                           SplitBars{"code128:FS-00042", "Code128", 2.5, 1}));

TEST(CodeMeasure, WhatCannotBeMeasuredSaysWhy) {
  const imaging::Plane flat(100, 100, 0.9f);
  const CodeCorners tiny{{{10, 10}, {14, 10}, {14, 14}, {10, 14}}};
  const CodeQuality linear = measure_code(flat, "Code128", tiny);
  EXPECT_FALSE(linear.measured);
  EXPECT_NE(linear.problem.find("shorter"), std::string::npos) << linear.problem;
  const CodeCorners wide{{{10, 50}, {90, 50}, {90, 50}, {10, 50}}};
  EXPECT_NE(measure_code(flat, "Code128", wide).problem.find("no bars"), std::string::npos);
  const CodeCorners off{{{60, 60}, {160, 60}, {160, 160}, {60, 160}}};
  EXPECT_NE(measure_code(flat, "QRCode", off).problem.find("off the image"), std::string::npos);
  EXPECT_FALSE(measure_code(imaging::Plane{}, "QRCode", off).measured);
}

TEST(CodeMeasure, GradeLettersFollowTheIsoBands) {
  EXPECT_EQ(grade_letter(4.0), 'A');
  EXPECT_EQ(grade_letter(3.5), 'A');
  EXPECT_EQ(grade_letter(3.4), 'B');
  EXPECT_EQ(grade_letter(1.5), 'C');
  EXPECT_EQ(grade_letter(0.5), 'D');
  EXPECT_EQ(grade_letter(0.4), 'F');
  EXPECT_TRUE(is_linear_format("EAN-13"));
  EXPECT_FALSE(is_linear_format("DataMatrix"));
}

}  // namespace
}  // namespace flutterscan::reader
