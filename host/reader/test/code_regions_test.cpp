// Where a latent looks like a code: found on dim paper and on cartons the
// paper finder cannot see, never on noise, shading or an object's edge.
#include "reader/code_regions.hpp"

#include <ZXing/BitMatrix.h>
#include <ZXing/MultiFormatWriter.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <string>
#include <vector>

#include "reader/code_reading.hpp"

namespace flutterscan::reader {
namespace {

/// Gaussian noise of `sigma` added to every sample of `plane` (fixed seed).
void add_noise(imaging::Plane& plane, double sigma, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> noise(0.0f, static_cast<float>(sigma));
  for (float& v : plane.pixels) v += noise(rng);
}

/// A 900 x 240 brown carton (0.22) with a Code 128 "FS-DIM" printed (0.05) on
/// cream paper dimmer than white (0.45) at columns [300, 640), rows [40, 200),
/// with noise of 0.02.
imaging::Plane carton_with_dim_label() {
  imaging::Plane carton(900, 240, 0.22f);
  const ZXing::BitMatrix bars = ZXing::MultiFormatWriter(ZXing::BarcodeFormat::Code128)
                                    .setMargin(0)
                                    .encode(L"FS-DIM", 280, 100);
  for (int y = 40; y < 200; ++y)
    for (int x = 300; x < 640; ++x) {
      const int bx = x - 330, by = y - 70;
      const bool bar =
          bx >= 0 && by >= 0 && bx < bars.width() && by < bars.height() && bars.get(bx, by);
      carton.at(x, y) = bar ? 0.05f : 0.45f;
    }
  add_noise(carton, 0.02, 7);
  return carton;
}

TEST(CodeRegions, ACodeOnDimPaperOnACartonIsFoundAndReadWhereThePaperFinderSeesNothing) {
  const imaging::Plane carton = carton_with_dim_label();
  const std::vector<LabelRegion> paper = find_paper_runs(carton);
  EXPECT_TRUE(paper.empty());
  const std::vector<LabelRegion> code = find_code_regions(carton);
  ASSERT_EQ(code.size(), 1u);
  // The region is the bars' extent, to within a cell.
  int first = carton.width, last = -1;
  for (int x = 0; x < carton.width; ++x)
    if (carton.at(x, 120) < 0.15f) first = std::min(first, x), last = std::max(last, x);
  ASSERT_LT(first, last);
  EXPECT_LE(code[0].begin, first);
  EXPECT_GE(code[0].begin, first - 16);
  EXPECT_GT(code[0].end, last);
  EXPECT_LE(code[0].end, last + 1 + 16);
  EXPECT_LE(code[0].across_begin, 70);
  EXPECT_GE(code[0].across_end, 170);
  EXPECT_FALSE(code[0].cut);
  const std::vector<LabelRegion> look = regions_to_read(paper, code);
  ASSERT_EQ(look.size(), 1u);
  const CodeReading reading = read_codes(carton, look, imaging::Direction::kPlusX, ReaderOptions{});
  EXPECT_EQ(code_texts(reading.readout), std::vector<std::string>{"FS-DIM"});
}

TEST(CodeRegions, NoiseShadingAndAnObjectsEdgesAreNotCodes) {
  imaging::Plane scene(640, 320, 0.0f);
  for (int y = 0; y < scene.height; ++y)
    for (int x = 0; x < scene.width; ++x) {
      const float shading = 0.2f + 0.4f * static_cast<float>(x) / scene.width;  // smooth
      const bool box = x >= 200 && x < 440 && y >= 80 && y < 240;               // edges only
      scene.at(x, y) = box ? 0.85f : shading;
    }
  add_noise(scene, 0.05, 11);
  EXPECT_TRUE(find_code_regions(scene).empty());
  imaging::Plane noise(640, 320, 0.4f);
  add_noise(noise, 0.08, 12);
  EXPECT_TRUE(find_code_regions(noise).empty());
  EXPECT_TRUE(find_code_regions(imaging::Plane(8, 8, 0.5f)).empty());
}

TEST(CodeRegions, AtTheFramesEdgeARegionIsCutAndTheRegionsReadSkipThoseInsidePaper) {
  const imaging::Plane carton = carton_with_dim_label();
  imaging::Plane shifted(420, 240, 0.22f);  // the label's last 120 columns fall outside
  for (int y = 0; y < 240; ++y)
    for (int x = 0; x < 420; ++x) shifted.at(x, y) = carton.at(x + 100, y);
  const std::vector<LabelRegion> code = find_code_regions(shifted);
  ASSERT_EQ(code.size(), 1u);
  EXPECT_TRUE(code[0].cut);

  const LabelRegion paper{100, 700, false, 0, 0};  // rows not measured: every row
  const LabelRegion inside{200, 400, false, 50, 150};
  const LabelRegion beyond{650, 800, false, 50, 150};
  const std::vector<LabelRegion> runs{paper}, found{inside, beyond};
  const std::vector<LabelRegion> look = regions_to_read(runs, found);
  ASSERT_EQ(look.size(), 2u);
  EXPECT_EQ(look[0].begin, 100);
  EXPECT_EQ(look[1].begin, 650);
}

TEST(CodeRegions, PaperRunsOneCodeSplitsAreJoinedAndTwoLabelsStayApart) {
  const LabelRegion left{100, 200, false, 40, 200}, right{300, 500, false, 40, 200};
  const LabelRegion other{700, 900, false, 40, 200};
  const std::vector<LabelRegion> runs{right, other, left};  // any order
  const LabelRegion bars{130, 470, false, 60, 180};
  const std::vector<LabelRegion> joined = join_runs_split_by_codes(runs, {&bars, 1});
  ASSERT_EQ(joined.size(), 2u);
  EXPECT_EQ(joined[0].begin, 100);
  EXPECT_EQ(joined[0].end, 500);
  EXPECT_EQ(joined[0].across_begin, 40);
  EXPECT_EQ(joined[0].across_end, 200);
  EXPECT_EQ(joined[1].begin, 700);
  // A code region that does not reach across the gap, or lies in other rows, joins nothing.
  const LabelRegion short_bars{130, 280, false, 60, 180};
  EXPECT_EQ(join_runs_split_by_codes(runs, {&short_bars, 1}).size(), 3u);
  const LabelRegion below{130, 470, false, 300, 400};
  EXPECT_EQ(join_runs_split_by_codes(runs, {&below, 1}).size(), 3u);
  // A region across the belt between two labels would join them, but the belt is not busy:
  // no region reaches across it on a real frame (CodeRegions.NoiseShading... above).
  const LabelRegion cut_run{0, 60, true, 40, 200}, beside{80, 150, false, 40, 200};
  const LabelRegion across{20, 120, false, 50, 190};
  const std::vector<LabelRegion> at_edge{cut_run, beside};
  const std::vector<LabelRegion> edge_joined = join_runs_split_by_codes(at_edge, {&across, 1});
  ASSERT_EQ(edge_joined.size(), 1u);
  EXPECT_TRUE(edge_joined[0].cut);
}

TEST(CodeRegions, ALabelWhoseNarrowSpacesAreLostFallsApartAndIsReadWhenJoined) {
  // A white label (0.9) on a belt (0.2); its Code 128's bars reach to 5 rows
  // from the paper's top and bottom (too few paper rows for a paper column),
  // and its spaces of one and two modules are grey (0.55, below the paper threshold),
  // as dim light's noise and the deblur's ringing leave them: the paper finder
  // sees the label's runs of wide spaces only.
  imaging::Plane scene(1000, 240, 0.2f);
  const ZXing::BitMatrix bars = ZXing::MultiFormatWriter(ZXing::BarcodeFormat::Code128)
                                    .setMargin(0)
                                    .encode(L"FS-00020", 0, 1);
  constexpr int kModule = 3, kLeft = 160, kTop = 45, kBottom = 195;
  const int right = kLeft + bars.width() * kModule;
  ASSERT_LT(right, 760);
  for (int y = 40; y < 200; ++y)
    for (int x = 100; x < right + 60; ++x) scene.at(x, y) = 0.9f;
  for (int m = 0; m < bars.width(); ++m) {
    const bool bar = bars.get(m, 0);
    int space = 0;  // the space's width in modules
    for (int k = m; k < bars.width() && !bars.get(k, 0); ++k) ++space;
    for (int k = m - 1; k >= 0 && !bars.get(k, 0); --k) ++space;
    const bool narrow_space = !bar && space <= 2;
    if (!bar && !narrow_space) continue;
    for (int y = kTop; y < kBottom; ++y)
      for (int x = kLeft + m * kModule; x < kLeft + (m + 1) * kModule; ++x)
        scene.at(x, y) = bar ? 0.05f : 0.55f;
  }
  add_noise(scene, 0.02, 21);
  const std::vector<LabelRegion> paper = find_paper_runs(scene);
  ASSERT_GE(paper.size(), 2u);  // the label in pieces
  const std::vector<LabelRegion> code = find_code_regions(scene);
  const std::vector<LabelRegion> joined = join_runs_split_by_codes(paper, code);
  ASSERT_EQ(joined.size(), 1u);
  EXPECT_LE(joined[0].begin, kLeft);
  EXPECT_GE(joined[0].end, right);
  const CodeReading reading =
      read_codes(scene, regions_to_read(joined, code), imaging::Direction::kPlusX, ReaderOptions{});
  EXPECT_EQ(code_texts(reading.readout), std::vector<std::string>{"FS-00020"});
}

}  // namespace
}  // namespace flutterscan::reader
