// Where a latent looks like a code: found on dim paper and on cartons the
// paper finder cannot see, never on noise, shading or an object's edge.
#include "reader/code_regions.hpp"

#include <ZXing/BitMatrix.h>
#include <ZXing/MultiFormatWriter.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "reader/code_reading.hpp"
#include "sim/scene.hpp"

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

TEST(CodeRegions, LowContrastPrintOnACartonInDimLightIsFoundOverItsWholeWidth) {
  // A Code 128 printed straight on brown card (0.13 on 0.24: contrast 0.11)
  // in the noise of dim light (0.05 per row, rows independent, as rows
  // deblurred on their own have it). A single row's cells stand under the
  // threshold; two neighbouring rows averaged carry the same print at half
  // the noise variance.
  imaging::Plane carton(900, 240, 0.24f);
  const ZXing::BitMatrix bars = ZXing::MultiFormatWriter(ZXing::BarcodeFormat::Code128)
                                    .setMargin(0)
                                    .encode(L"FS-CARD", 400, 100);
  for (int y = 0; y < bars.height(); ++y)
    for (int x = 0; x < bars.width(); ++x)
      if (bars.get(x, y)) carton.at(250 + x, 70 + y) = 0.13f;
  add_noise(carton, 0.05, 9);
  const std::vector<LabelRegion> code = find_code_regions(carton);
  ASSERT_EQ(code.size(), 1u);  // one region, not pieces of the code
  // Within two cells of the bars' ends (the decode window adds 24 px to each side).
  EXPECT_LE(code[0].begin, 250 + 32);
  EXPECT_GE(code[0].end, 250 + bars.width() - 32);
}

/// A 1000 x 320 card (0.6) with patches of 2-px bars (0.1) at columns [x, x + 160)
/// and rows [y, y + 100), noise 0.02.
imaging::Plane card_with_bar_patches(const std::vector<std::pair<int, int>>& patches) {
  imaging::Plane card(1000, 320, 0.6f);
  for (const auto& [px, py] : patches)
    for (int y = py; y < py + 100; ++y)
      for (int x = px; x < px + 160; ++x)
        if ((x - px) % 4 < 2) card.at(x, y) = 0.1f;
  add_noise(card, 0.02, 3);
  return card;
}

TEST(CodeRegions, PiecesSideBySideInTheSameRowsAreOneCodeAndFarOnesTwo) {
  // 96 px apart in the same rows (a linear code's wide bars between them): one.
  const auto near = find_code_regions(card_with_bar_patches({{96, 64}, {352, 64}}));
  ASSERT_EQ(near.size(), 1u);
  EXPECT_EQ(near[0].begin, 96);
  EXPECT_EQ(near[0].end, 512);
  // 208 px apart, or in rows they do not share: two.
  EXPECT_EQ(find_code_regions(card_with_bar_patches({{96, 64}, {464, 64}})).size(), 2u);
  EXPECT_EQ(find_code_regions(card_with_bar_patches({{96, 16}, {352, 192}})).size(), 2u);
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

TEST(CodeRegions, TheBeltBesideALabelInABandOfDeblurredRowsIsNotBusy) {
  // What the session's deblur leaves in dim light: rows it found flat filled
  // with one value (0.3); a band of rows [100, 212) deblurred, the belt's noise
  // in it (0.056, as joint Wiener's at 300 e-) and the dim label of
  // carton_with_dim_label() in it; and single rows of belt deblurred among the
  // flat ones (the flat-row test lets about one in a hundred through), whose
  // cells change in one sampled row of four.
  const imaging::Plane label = carton_with_dim_label();
  imaging::Plane frame(900, 320, 0.3f);
  std::mt19937 rng(5);
  std::normal_distribution<float> noise(0.0f, 0.056f);
  for (int y = 0; y < frame.height; ++y) {
    const bool band = y >= 100 && y < 212;
    if (!band && y % 24 != 8) continue;  // rows 8, 32, 56, 80, 224, ...: sampled ones
    for (int x = 0; x < frame.width; ++x) {
      const bool on_label = band && x >= 300 && x < 640 && y - 60 >= 40 && y - 60 < 200;
      frame.at(x, y) = (on_label ? label.at(x, y - 60) : 0.3f) + noise(rng);
    }
  }
  const std::vector<LabelRegion> code = find_code_regions(frame);
  ASSERT_FALSE(code.empty());
  for (const LabelRegion& r : code) {  // the code's columns (330..610) and a cell or two
    EXPECT_GE(r.begin, 300 - 32) << r.begin << ".." << r.end;
    EXPECT_LE(r.end, 640 + 32) << r.begin << ".." << r.end;
  }
}

/// A `kind` scene ("code128", "qr", "text") of `content`, `width` x `height`, with noise of 0.02.
imaging::Plane scene(sim::SceneKind kind, const std::string& content, int width, int height) {
  sim::SceneSpec spec;
  spec.kind = kind;
  spec.content = content;
  spec.width = width;
  spec.height = height;
  spec.module_px = 2.5;
  auto plane = sim::render_scene(spec);
  EXPECT_TRUE(plane.ok()) << plane.error();
  add_noise(plane.value(), 0.02, 3);
  return plane.value();
}

TEST(CodeRegions, BarsLookMoreLikeALinearCodeThanTextAMatrixCodeOrNoise) {
  const int w = 480, h = 240;
  const LabelRegion whole{0, w, false, 0, 0};
  auto likeness = [&](const imaging::Plane& p) { return bar_likeness(p, {&whole, 1}).front(); };
  const imaging::Plane bars = scene(sim::SceneKind::kCode128, "PARCEL-0042", w, h);
  const imaging::Plane text = scene(sim::SceneKind::kText, "SHIP TO 4410 RIVERSIDE DR", w, h);
  const imaging::Plane qr = scene(sim::SceneKind::kQr, "https://example.com/parcel/0042", w, h);
  imaging::Plane noise(w, h, 0.5f);
  add_noise(noise, 0.1, 5);
  // The same bars turned a quarter: steps across the rows, repeating along them.
  imaging::Plane turned(h, w);
  for (int y = 0; y < w; ++y)
    for (int x = 0; x < h; ++x) turned.at(x, y) = bars.at(y, h - 1 - x);
  const LabelRegion turned_whole{0, h, false, 0, 0};
  const double along = bar_likeness(turned, {&turned_whole, 1}).front();
  std::printf("bar likeness: bars %.2f, turned %.2f, text %.2f, qr %.2f, noise %.2f\n",
              likeness(bars), along, likeness(text), likeness(qr), likeness(noise));
  EXPECT_GT(likeness(bars), 0.8);
  EXPECT_GT(along, 0.8);
  for (const double other : {likeness(text), likeness(qr), likeness(noise)})
    EXPECT_LT(other, likeness(bars) - 0.2);
  EXPECT_LT(likeness(noise), 0.1);
  const imaging::Plane flat(w, h, 0.5f);
  EXPECT_EQ(likeness(flat), 0.0);
}

}  // namespace
}  // namespace flutterscan::reader
