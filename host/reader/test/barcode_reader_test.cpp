// The barcode reader survives ZXing's own assertions: Debian builds ZXing with
// assert() on, and its Micro QR sampler fails one on some deblurred frames.
#include "reader/barcode_reader.hpp"

#include <ZXing/BitMatrix.h>
#include <ZXing/MultiFormatWriter.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numbers>
#include <random>
#include <string>
#include <thread>

#include "reader/assertion_guard.hpp"
#include "sim/scene.hpp"

// glibc's assertion handler, which assert() calls (not declared under NDEBUG).
extern "C" [[noreturn]] void __assert_fail(const char* assertion, const char* file,
                                           unsigned int line, const char* function) noexcept;

namespace flutterscan::reader {
namespace {

/// A binary PGM (P5, 8-bit) as reflectance 0..1.
imaging::Plane read_pgm(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string magic;
  int width = 0, height = 0, max_value = 0;
  in >> magic >> width >> height >> max_value;
  in.get();
  imaging::Plane plane(width, height);
  for (float& v : plane.pixels) v = static_cast<float>(in.get()) / static_cast<float>(max_value);
  EXPECT_TRUE(in.good() && magic == "P5") << path;
  return plane;
}

TEST(AssertionGuard, AFailedAssertionInsideReturnsItsTextAndLaterCallsRunNormally) {
  int reached = 0;
  const std::string failure = run_catching_assertions([&] {
    ++reached;
    __assert_fail("frames > 0", "camera.cpp", 42, "void f()");
    ++reached;  // not reached
  });
  EXPECT_EQ(reached, 1);
  EXPECT_NE(failure.find("camera.cpp:42"), std::string::npos) << failure;
  EXPECT_NE(failure.find("Assertion `frames > 0' failed"), std::string::npos) << failure;
  EXPECT_EQ(run_catching_assertions([&] { ++reached; }), "");
  EXPECT_EQ(reached, 2);
}

TEST(AssertionGuard, EachThreadReturnsToItsOwnGuard) {
  std::string in_thread, here;
  std::thread other(
      [&] { in_thread = run_catching_assertions([] { __assert_fail("a", "a.cpp", 1, "fa"); }); });
  here = run_catching_assertions([] { __assert_fail("b", "b.cpp", 2, "fb"); });
  other.join();
  EXPECT_NE(in_thread.find("a.cpp:1"), std::string::npos) << in_thread;
  EXPECT_NE(here.find("b.cpp:2"), std::string::npos) << here;
}

// A decode's time budget: the first window's first view is always read; past
// the budget no window is started and none read in another view; every window
// left with nothing read is listed, in the order given.
TEST(BarcodeReader, WindowsBeyondTheTimeBudgetAreListedNotRead) {
  auto spec = sim::parse_scene("code128:BUDGET-1");
  ASSERT_TRUE(spec.ok());
  spec.value().width = 400;
  spec.value().height = 200;
  spec.value().module_px = 2;
  auto label = sim::render_scene(spec.value());
  ASSERT_TRUE(label.ok()) << label.error();
  // The label, then two windows of blank paper.
  imaging::Plane frame(3 * 400, 200);
  std::fill(frame.pixels.begin(), frame.pixels.end(), 0.9f);
  for (int y = 0; y < 200; ++y)
    for (int x = 0; x < 400; ++x) frame.at(x, y) = label.value().at(x, y);
  const std::vector<DecodeWindow> windows = {
      {0, 0, 400, 200}, {400, 0, 400, 200}, {800, 0, 400, 200}};
  const BarcodeReadout every = read_barcodes(frame, kDefaultSymbologies, true, windows);
  ASSERT_EQ(every.codes.size(), 1u);
  EXPECT_TRUE(every.windows_left.empty() && every.windows_cut.empty());
  const BarcodeReadout bounded = read_barcodes(frame, kDefaultSymbologies, true, windows, {1e-3});
  ASSERT_EQ(bounded.codes.size(), 1u);
  EXPECT_EQ(bounded.codes[0].text, "BUDGET-1");
  EXPECT_EQ(bounded.windows_left, (std::vector<std::size_t>{1, 2}));
  EXPECT_TRUE(bounded.windows_cut.empty());
  // The label last: the blank window's first view is read, nothing else.
  const std::vector<DecodeWindow> label_last = {windows[1], windows[0]};
  const BarcodeReadout late = read_barcodes(frame, kDefaultSymbologies, true, label_last, {1e-3});
  EXPECT_TRUE(late.codes.empty());
  EXPECT_EQ(late.windows_cut, (std::vector<std::size_t>{0}));
  EXPECT_EQ(late.windows_left, (std::vector<std::size_t>{1}));
  // At a view cost of 0.01 ms a pixel, a deadline a second away holds the
  // label's window (0.8 s) but no more the whole frame's (2.4 s), and still one
  // of 10 x 10 (1 ms): the frame's is left, the smaller after it is read.
  const std::vector<DecodeWindow> by_cost = {windows[0], {0, 0, 1200, 200}, {900, 50, 10, 10}};
  const BarcodeReadout costed = read_barcodes(frame, kDefaultSymbologies, true, by_cost,
                                              {.deadline_ms = 1000, .view_ms_per_mpx = 1e4});
  ASSERT_EQ(costed.codes.size(), 1u);
  EXPECT_EQ(costed.windows_left, (std::vector<std::size_t>{1}));
  EXPECT_TRUE(costed.windows_cut.empty());
  // A deadline that holds no view leaves even the first window.
  const BarcodeReadout due = read_barcodes(frame, kDefaultSymbologies, true, windows,
                                           {.ms = 1000, .deadline_ms = 0, .view_ms_per_mpx = 1});
  EXPECT_TRUE(due.codes.empty());
  EXPECT_EQ(due.windows_left, (std::vector<std::size_t>{0, 1, 2}));
}

TEST(BarcodeReader, AnImageThatTripsZXingsMicroQrAssertionIsReportedNotFatal) {
  // A crop of a deblurred 1080p sim frame on which ZXing 1.4's Micro QR
  // sampler (FindConcentricPatternCorners -> intersect) aborted a session.
  const imaging::Plane image =
      read_pgm(FLUTTERSCAN_SOURCE_DIR "/host/reader/test/data/zxing_micro_qr_assertion.pgm");
  ASSERT_EQ(image.width, 41);
  const BarcodeReadout micro_qr = read_barcodes(image, "MicroQRCode");
  EXPECT_NE(micro_qr.decoder_fault.find("RegressionLine"), std::string::npos)
      << "ZXing no longer asserts on this image: '" << micro_qr.decoder_fault << "'";
  EXPECT_TRUE(micro_qr.codes.empty());
  // The default symbologies leave Micro QR out, and the reader still works.
  const BarcodeReadout defaults = read_barcodes(image);
  EXPECT_EQ(defaults.decoder_fault, "");
}

TEST(BarcodeReader, ACodeTurnedBy90DegreesIsReadOnlyWithTryRotate) {
  const ZXing::BitMatrix bars = ZXing::MultiFormatWriter(ZXing::BarcodeFormat::Code128)
                                    .setMargin(20)
                                    .encode(L"FS-ROTATE-7", 600, 120);
  // Bars running along the rows: the code turned by 90 degrees.
  imaging::Plane turned(bars.height(), bars.width());
  for (int y = 0; y < bars.height(); ++y)
    for (int x = 0; x < bars.width(); ++x) turned.at(y, x) = bars.get(x, y) ? 0.05f : 0.9f;
  const BarcodeReadout with = read_barcodes(turned, "Code128", true);
  ASSERT_EQ(with.codes.size(), 1u);
  EXPECT_EQ(with.codes[0].text, "FS-ROTATE-7");
  EXPECT_TRUE(read_barcodes(turned, "Code128", false).codes.empty());
}

/// Code 128 `text` (`length` x `height` px with its quiet zones, dark on 0.9)
/// laid into `into` at (x, y), its bars across the rows, or (`turned`) along them.
void lay_code128(imaging::Plane& into, const std::wstring& text, int length, int height, int x,
                 int y, bool turned) {
  const ZXing::BitMatrix bars = ZXing::MultiFormatWriter(ZXing::BarcodeFormat::Code128)
                                    .setMargin(10)
                                    .encode(text, length, height);
  for (int b = 0; b < bars.height(); ++b)
    for (int a = 0; a < bars.width(); ++a)
      (turned ? into.at(x + b, y + a) : into.at(x + a, y + b)) = bars.get(a, b) ? 0.05f : 0.9f;
}

TEST(BarcodeReader, ATilesLinearCodesAreFoundOnEveryEighthRowOrColumnInTheirPlace) {
  imaging::Plane print(640, 640, 0.5f);
  lay_code128(print, L"FS-UPRIGHT-1", 300, 70, 40, 407, false);
  lay_code128(print, L"FS-TURNED-2", 300, 70, 500, 123, true);
  lay_code128(print, L"FS-SHORT-3", 300, 6, 40, 603, false);  // one row looked at, not two
  DecodeWindow thorough{0, 0, 640, 640};
  thorough.views = 1;
  thorough.second_decoder = false;
  DecodeWindow every_eighth = thorough;
  every_eighth.linear_row_step = 8;
  const BarcodeReadout all = read_barcodes(print, "Code128", true, {&thorough, 1});
  const BarcodeReadout stepped = read_barcodes(print, "Code128", true, {&every_eighth, 1});
  ASSERT_EQ(all.codes.size(), 3u);
  ASSERT_EQ(stepped.codes.size(), 2u);
  // What a thorough view costs a pixel is followed on thorough views only.
  EXPECT_EQ(all.first_view_px, 640 * 640);
  EXPECT_EQ(stepped.first_view_px, 0);
  for (const DecodedCode& code : stepped.codes) {
    const auto same = std::find_if(all.codes.begin(), all.codes.end(),
                                   [&](const DecodedCode& c) { return c.text == code.text; });
    ASSERT_NE(same, all.codes.end()) << code.text;
    EXPECT_NE(code.text, "FS-SHORT-3");
    // Where it lies and which way it reads: as the thorough scan says, within
    // the rows (or columns) between two scanned ones.
    EXPECT_NEAR(code.centre_x, same->centre_x, 8) << code.text;
    EXPECT_NEAR(code.centre_y, same->centre_y, 8) << code.text;
    EXPECT_NEAR(code.orientation_deg, same->orientation_deg, 1) << code.text;
    for (std::size_t c = 0; c < 4; ++c) {  // ZXing's corner order: its top edge first
      EXPECT_NEAR(code.quality.corners[c].x, same->quality.corners[c].x, 8) << code.text << c;
      EXPECT_NEAR(code.quality.corners[c].y, same->quality.corners[c].y, 8) << code.text << c;
    }
  }
  // A matrix code in the same window is looked for on every pixel.
  const ZXing::BitMatrix qr =
      ZXing::MultiFormatWriter(ZXing::BarcodeFormat::QRCode).setMargin(4).encode(L"FS-QR", 0, 0);
  imaging::Plane matrix(640, 640, 0.9f);
  for (int y = 0; y < qr.height() * 4; ++y)
    for (int x = 0; x < qr.width() * 4; ++x)
      if (qr.get(x / 4, y / 4)) matrix.at(300 + x, 301 + y) = 0.05f;
  const BarcodeReadout square = read_barcodes(matrix, "QRCode,Code128", true, {&every_eighth, 1});
  ASSERT_EQ(square.codes.size(), 1u);
  EXPECT_EQ(square.codes[0].text, "FS-QR");
}

/// A belt (0.35) `height` rows tall with white labels 160 rows tall from row
/// `top`, each carrying a Code 128 code, starting at `starts` (the last one may
/// run past the right edge).
imaging::Plane belt_with_labels(const std::vector<int>& starts, int width, int height = 200,
                                int top = 20) {
  imaging::Plane belt(width, height, 0.35f);
  int n = 0;
  for (int start : starts) {
    const std::wstring text = L"FS-WINDOW-" + std::to_wstring(++n);
    const ZXing::BitMatrix bars = ZXing::MultiFormatWriter(ZXing::BarcodeFormat::Code128)
                                      .setMargin(10)
                                      .encode(text, 300, 120);
    for (int y = 0; y < 160; ++y)
      for (int x = 0; x < 320 && start + x < width; ++x) {
        const int bx = x - 10, by = y - 20;
        const bool bar =
            bx >= 0 && by >= 0 && bx < bars.width() && by < bars.height() && bars.get(bx, by);
        belt.at(start + x, top + y) = bar ? 0.05f : 0.9f;
      }
  }
  return belt;
}

/// A 340 x 160 card of reflectance `card_reflectance` with a Code 128 of
/// `text` (300 x 120 px with its quiet zones) printed in `ink` at (20, 20).
imaging::Plane code_on_card(const std::wstring& text, float card_reflectance, float ink) {
  const ZXing::BitMatrix bars =
      ZXing::MultiFormatWriter(ZXing::BarcodeFormat::Code128).setMargin(10).encode(text, 300, 120);
  imaging::Plane card(340, 160, card_reflectance);
  for (int y = 0; y < bars.height(); ++y)
    for (int x = 0; x < bars.width(); ++x)
      if (bars.get(x, y)) card.at(20 + x, 20 + y) = ink;
  return card;
}

TEST(BarcodeReader, AShortCodeLeaningTwelveDegreesIsReadTurnedUpright) {
  // A Code 128 40 px tall and 300 px long, its bars leaning 12 degrees (lower
  // ends toward larger x): its ends lie 64 px apart across the rows, so no row
  // crosses it whole.
  const double lean = 12 * std::numbers::pi / 180;
  const ZXing::BitMatrix bars = ZXing::MultiFormatWriter(ZXing::BarcodeFormat::Code128)
                                    .setMargin(10)
                                    .encode(L"TURN-12", 300, 40);
  imaging::Plane card(500, 260, 0.85f);
  const double cx = 250, cy = 130;
  for (int y = 0; y < card.height; ++y)
    for (int x = 0; x < card.width; ++x) {
      const double qx = x + 0.5 - cx, qy = y + 0.5 - cy;  // along the code, then along its bars
      const double bx = qx * std::cos(lean) - qy * std::sin(lean) + bars.width() / 2.0;
      const double by = qx * std::sin(lean) + qy * std::cos(lean) + bars.height() / 2.0;
      if (bx >= 0 && by >= 0 && bx < bars.width() && by < bars.height() &&
          bars.get(static_cast<int>(bx), static_cast<int>(by)))
        card.at(x, y) = 0.05f;
    }
  const DecodeWindow whole{0, 0, card.width, card.height};
  EXPECT_TRUE(read_barcodes(card, kDefaultSymbologies, true, {&whole, 1}).codes.empty());
  EXPECT_TRUE(read_barcodes_turned(card, whole, -lean, kDefaultSymbologies, true).codes.empty());
  const BarcodeReadout turned = read_barcodes_turned(card, whole, lean, kDefaultSymbologies, true);
  ASSERT_EQ(turned.codes.size(), 1u);
  EXPECT_EQ(turned.codes[0].text, "TURN-12");
  // Where it lies, in the card's coordinates.
  EXPECT_NEAR(turned.codes[0].centre_x, cx - 0.5, 4);
  EXPECT_NEAR(turned.codes[0].centre_y, cy - 0.5, 4);
  EXPECT_LT(turned.codes[0].min_x, cx - 100);
  EXPECT_GT(turned.codes[0].max_x, cx + 100);
}

TEST(BarcodeReader, DarkPrintTheLinearViewCannotSeparateIsReadOnTheSrgbView) {
  // Grey print on dark card: reflectance 0.045 and 0.012 are 11 and 3 of 255
  // in linear light (too little range for ZXing's binarizer), 60 and 28 sRGB-encoded.
  imaging::Plane card = code_on_card(L"DARK-01", 0.045f, 0.012f);
  const BarcodeReadout readout = read_barcodes(card);
  ASSERT_EQ(readout.codes.size(), 1u);
  EXPECT_EQ(readout.codes[0].text, "DARK-01");
  EXPECT_EQ(readout.codes[0].luminance, LuminanceView::kSrgb);
  // A window read in its first view only does not get to the sRGB view.
  DecodeWindow first_view{0, 0, card.width, card.height, 1};
  EXPECT_TRUE(read_barcodes(card, kDefaultSymbologies, true, {&first_view, 1}).codes.empty());
  first_view.views = 2;
  EXPECT_EQ(read_barcodes(card, kDefaultSymbologies, true, {&first_view, 1}).codes.size(), 1u);
  // Print the linear view reads is read there, once.
  for (float& v : card.pixels) v = v > 0.03f ? 0.9f : 0.05f;
  const BarcodeReadout bright = read_barcodes(card);
  ASSERT_EQ(bright.codes.size(), 1u);
  EXPECT_EQ(bright.codes[0].luminance, LuminanceView::kLinear);
}

TEST(BarcodeReader, GreyInkOnGreyCardIsReadFromItsBlackLevel) {
  // Ink that is not black on card that is not white: reflectance 0.10 and 0.16
  // are 26 and 41 of 255 in linear light and 89 and 112 sRGB-encoded, both
  // under the 24 levels ZXing's local binarizer takes for print; encoded from
  // the window's black level (0.10) they are 0 and 73.
  const BarcodeReadout readout = read_barcodes(code_on_card(L"GREY-02", 0.16f, 0.10f));
  ASSERT_EQ(readout.codes.size(), 1u);
  EXPECT_EQ(readout.codes[0].text, "GREY-02");
  EXPECT_EQ(readout.codes[0].luminance, LuminanceView::kSrgbFromBlack);
}

TEST(BarcodeReader, ALabelDarkerThanTheBeltBesideItIsReadToItsPaper) {
  // Grey label stock (0.15) in a window whose rows are mostly a brighter belt
  // (0.5): ZXing thresholds a linear code's row by the row's histogram, whose
  // tallest peak is then the belt; the threshold falls between the paper and
  // the belt and the paper is taken for ink in the first three views. Encoded
  // to the paper beside each pixel, the label is black on white.
  imaging::Plane window(1000, 160, 0.5f);
  const imaging::Plane card = code_on_card(L"KRAFT-7", 0.15f, 0.04f);
  for (int y = 0; y < card.height; ++y)
    for (int x = 0; x < card.width; ++x) window.at(330 + x, y) = card.at(x, y);
  const BarcodeReadout readout = read_barcodes(window);
  ASSERT_EQ(readout.codes.size(), 1u);
  EXPECT_EQ(readout.codes[0].text, "KRAFT-7");
  EXPECT_EQ(readout.codes[0].luminance, LuminanceView::kSrgbToPaper);
  EXPECT_EQ(luminance_view_name(readout.codes[0].luminance), "srgb-to-paper");
  // The card alone, without the belt on its rows, is read before that view.
  const BarcodeReadout alone = read_barcodes(card);
  ASSERT_EQ(alone.codes.size(), 1u);
  EXPECT_NE(alone.codes[0].luminance, LuminanceView::kSrgbToPaper);
  // Matrix symbologies alone: the paper view is not tried (ZXing binarizes
  // them by local blocks), so the label stays unread.
  EXPECT_TRUE(read_barcodes(window, "QRCode,DataMatrix").codes.empty());
}

TEST(BarcodeReader, ANoisyQrCodeIsReadSmoothedOverItsModules) {
  // A QR code of 3 px modules, ink 0.05 on paper 0.85, with noise of 0.25 rms
  // in each pixel (a deblurred latent's at low light): ZXing samples every
  // module at one pixel, so in the first four views a module's sample is as
  // likely as not on the wrong side of its threshold somewhere in the symbol.
  // Smoothed over a module's centre, the samples carry a third of the noise.
  const ZXing::BitMatrix modules = ZXing::MultiFormatWriter(ZXing::BarcodeFormat::QRCode)
                                       .setMargin(4)
                                       .encode(L"FS-SMOOTH-QR-0042", 1, 1);
  constexpr int kModulePx = 3;
  int four_views = 0, five_views = 0;
  for (unsigned seed = 1; seed <= 10; ++seed) {
    imaging::Plane code(modules.width() * kModulePx, modules.height() * kModulePx);
    std::mt19937 rng(seed);
    std::normal_distribution<float> noise(0.0f, 0.25f);
    for (int y = 0; y < code.height; ++y)
      for (int x = 0; x < code.width; ++x)
        code.at(x, y) = (modules.get(x / kModulePx, y / kModulePx) ? 0.05f : 0.85f) + noise(rng);
    DecodeWindow window{0, 0, code.width, code.height, kLuminanceViews - 1};
    four_views += !read_barcodes(code, "QRCode", false, {&window, 1}).codes.empty();
    const BarcodeReadout readout = read_barcodes(code, "QRCode", false);
    if (readout.codes.empty()) continue;
    EXPECT_EQ(readout.codes[0].text, "FS-SMOOTH-QR-0042");
    EXPECT_EQ(readout.codes[0].luminance, LuminanceView::kSmoothedFromBlack);
    EXPECT_EQ(luminance_view_name(readout.codes[0].luminance), "smoothed-from-black");
    ++five_views;
  }
  EXPECT_EQ(four_views, 0);
  EXPECT_GE(five_views, 8);
}

TEST(BarcodeReader, ALinearSymbolThatEndsAtTheWindowsEdgeIsNotTakenForARead) {
  // An EAN-13 of 3-px modules on white paper with its quiet zones: read.
  const ZXing::BitMatrix bars = ZXing::MultiFormatWriter(ZXing::BarcodeFormat::EAN13)
                                    .setMargin(0)
                                    .encode(L"4006381333931", 285, 90);
  auto label = [&](int left, int right) {
    imaging::Plane paper(left + bars.width() + right, 130, 0.9f);
    for (int y = 0; y < bars.height(); ++y)
      for (int x = 0; x < bars.width(); ++x)
        if (bars.get(x, y)) paper.at(left + x, 20 + y) = 0.05f;
    return paper;
  };
  const BarcodeReadout whole = read_barcodes(label(40, 40), "EAN-13");
  ASSERT_EQ(whole.codes.size(), 1u);
  EXPECT_EQ(whole.codes[0].text, "4006381333931");
  // The same symbol ending at the image's last column or starting at its
  // first: its quiet zone is not in the image, and whatever the decoder makes
  // of it is not a read.
  EXPECT_TRUE(read_barcodes(label(40, 0), "EAN-13").codes.empty());
  EXPECT_TRUE(read_barcodes(label(0, 40), "EAN-13").codes.empty());
  // In a window of a wider image the same holds at the window's edge.
  const imaging::Plane wide = label(40, 40);
  const DecodeWindow cut{0, 0, 40 + bars.width(), wide.height};
  EXPECT_TRUE(read_barcodes(wide, "EAN-13", true, {&cut, 1}).codes.empty());
}

TEST(BarcodeReader, PaperRunsFindLabelsAndFlagThoseCutByTheFrame) {
  const imaging::Plane image = belt_with_labels({60, 500, 980}, 1200);
  const auto runs = find_paper_runs(image);
  ASSERT_EQ(runs.size(), 3u);
  EXPECT_EQ(runs[0].begin, 60);
  EXPECT_EQ(runs[0].end, 380);
  EXPECT_FALSE(runs[0].cut);
  EXPECT_TRUE(runs[2].cut);  // runs to the right edge
  EXPECT_EQ(runs[2].end, 1200);
  EXPECT_EQ(runs[0].across_begin, 20);  // the label's rows
  EXPECT_EQ(runs[0].across_end, 180);
  EXPECT_EQ(runs[1].begin, 500);
  EXPECT_FALSE(runs[1].cut);
}

// A label leaving the frame with its bars at the edge: its paper columns end
// short of the last column (above and below the bars, fewer than 5% of the
// frame's rows are paper), but the label goes on past it.
TEST(BarcodeReader, ALabelWhoseBarsReachTheFramesEdgeIsCut) {
  for (const int bars_wide : {12, 40}) {  // within max_gap of the edge, and wider
    imaging::Plane scene(900, 600, 0.2f);
    for (int y = 40; y < 160; ++y)
      for (int x = 600; x < 900; ++x) scene.at(x, y) = 0.9f;
    for (int y = 50; y < 150; ++y)  // bars from its paper's top and bottom margin to the edge
      for (int x = 900 - bars_wide; x < 900; ++x) scene.at(x, y) = (x / 3) % 2 ? 0.05f : 0.3f;
    const auto runs = find_paper_runs(scene);
    ASSERT_EQ(runs.size(), 1u) << bars_wide;
    EXPECT_EQ(runs[0].end, 900 - bars_wide);
    EXPECT_TRUE(runs[0].cut) << bars_wide;
  }
  // A label that ends before the edge, the belt beside it: whole.
  imaging::Plane whole(900, 600, 0.2f);
  for (int y = 40; y < 160; ++y)
    for (int x = 600; x < 860; ++x) whole.at(x, y) = 0.9f;
  const auto runs = find_paper_runs(whole);
  ASSERT_EQ(runs.size(), 1u);
  EXPECT_FALSE(runs[0].cut);
}

TEST(BarcodeReader, ALabelWhoseNarrowSpacesFallBelowPaperIsOneRunAndALabelBesideItAnother) {
  // White labels (0.9) on a belt (0.2), 80 px apart. The first's Code 128
  // bars reach to 5 rows from its paper's top and bottom (too few paper rows
  // for a paper column), and its spaces of one and two modules are grey
  // (0.55, below the paper threshold), as dim light's noise and the deblur's
  // ringing leave them: its bars make dark gaps far wider than max_gap.
  imaging::Plane scene(1100, 240, 0.2f);
  const ZXing::BitMatrix bars = ZXing::MultiFormatWriter(ZXing::BarcodeFormat::Code128)
                                    .setMargin(0)
                                    .encode(L"FS-00020", 0, 1);
  constexpr int kModule = 3, kLeft = 160, kTop = 45, kBottom = 195;
  const int right = kLeft + bars.width() * kModule;
  const int paper_end = right + 60, second = paper_end + 80;
  ASSERT_LT(second + 200, scene.width);
  for (int y = 40; y < 200; ++y) {
    for (int x = 100; x < paper_end; ++x) scene.at(x, y) = 0.9f;
    for (int x = second; x < second + 200; ++x) scene.at(x, y) = 0.9f;
  }
  int widest_gap = 0, gap = 0;
  for (int m = 0; m < bars.width(); ++m) {
    int space = 0;  // the space's width in modules
    for (int k = m; k < bars.width() && !bars.get(k, 0); ++k) ++space;
    for (int k = m - 1; k >= 0 && !bars.get(k, 0); --k) ++space;
    const bool bar = bars.get(m, 0);
    gap = bar || space <= 2 ? gap + kModule : 0;
    widest_gap = std::max(widest_gap, gap);
    if (!bar && space > 2) continue;
    for (int y = kTop; y < kBottom; ++y)
      for (int x = kLeft + m * kModule; x < kLeft + (m + 1) * kModule; ++x)
        scene.at(x, y) = bar ? 0.05f : 0.55f;
  }
  ASSERT_GT(widest_gap, 2 * 16);  // the first label's bars split a run of max_gap 16
  std::mt19937 rng(21);
  std::normal_distribution<float> noise(0.0f, 0.02f);
  for (float& v : scene.pixels) v += noise(rng);

  const std::vector<LabelRegion> runs = find_paper_runs(scene);
  ASSERT_EQ(runs.size(), 2u);
  EXPECT_LE(runs[0].begin, 100);
  EXPECT_GE(runs[0].end, paper_end - 1);
  EXPECT_LE(runs[0].end, paper_end + 1);
  EXPECT_GE(runs[1].begin, second - 1);
  const auto windows = decode_windows(runs, scene.width, scene.height, imaging::Direction::kPlusX);
  const BarcodeReadout readout = read_barcodes(scene, "Code128", false, windows);
  ASSERT_EQ(readout.codes.size(), 1u);
  EXPECT_EQ(readout.codes[0].text, "FS-00020");
}

TEST(BarcodeReader, DecodingThePaperAloneReadsWhatTheWholeFrameReads) {
  const imaging::Plane image = belt_with_labels({60, 500, 900}, 1240, 600, 300);
  const auto windows =
      decode_windows(find_paper_runs(image), image.width, image.height, imaging::Direction::kPlusX);
  ASSERT_EQ(windows.size(), 3u);
  EXPECT_EQ(windows[0].x, 60 - 24);
  EXPECT_EQ(windows[0].width, 320 + 48);
  EXPECT_EQ(windows[0].y, 300 - 24);  // the label's rows and a margin, not the frame's
  EXPECT_EQ(windows[0].height, 160 + 48);
  const BarcodeReadout whole = read_barcodes(image, "Code128");
  const BarcodeReadout paper = read_barcodes(image, "Code128", true, windows);
  ASSERT_EQ(whole.codes.size(), 3u);
  ASSERT_EQ(paper.codes.size(), 3u);
  for (const DecodedCode& w : whole.codes) {
    const auto same = std::find_if(paper.codes.begin(), paper.codes.end(),
                                   [&](const DecodedCode& p) { return p.text == w.text; });
    ASSERT_NE(same, paper.codes.end()) << w.text;
    EXPECT_NEAR(same->centre_x, w.centre_x, 1.0) << w.text;  // in the frame's coordinates
    EXPECT_NEAR(same->centre_y, w.centre_y, 1.0) << w.text;
  }
  // A window on the belt alone reads nothing.
  const DecodeWindow belt_only{400, 0, 80, image.height};
  EXPECT_TRUE(read_barcodes(image, "Code128", true, {&belt_only, 1}).codes.empty());
}

TEST(BarcodeReader, DecodeWindowsFollowTheMotionDirection) {
  const std::vector<LabelRegion> runs = {{100, 300, false}};
  // Along the motion the run is [100, 300) in the motion frame; 24 px margins.
  const auto minus_x = decode_windows(runs, 1000, 400, imaging::Direction::kMinusX);
  ASSERT_EQ(minus_x.size(), 1u);
  EXPECT_EQ(minus_x[0].x, 1000 - 324);
  EXPECT_EQ(minus_x[0].width, 248);
  EXPECT_EQ(minus_x[0].y, 0);
  EXPECT_EQ(minus_x[0].height, 400);
  const auto plus_y = decode_windows(runs, 1000, 400, imaging::Direction::kPlusY);
  EXPECT_EQ(plus_y[0].x, 0);
  EXPECT_EQ(plus_y[0].width, 1000);
  EXPECT_EQ(plus_y[0].y, 76);
  EXPECT_EQ(plus_y[0].height, 248);
  const auto minus_y = decode_windows(runs, 1000, 400, imaging::Direction::kMinusY);
  EXPECT_EQ(minus_y[0].y, 400 - 324);
  // Rows measured across the motion: the window spans them and a margin.
  const std::vector<LabelRegion> rows = {{100, 300, false, 50, 150}};
  const auto plus_x_rows = decode_windows(rows, 1000, 400, imaging::Direction::kPlusX);
  EXPECT_EQ(plus_x_rows[0].y, 26);
  EXPECT_EQ(plus_x_rows[0].height, 148);
  const auto minus_y_rows = decode_windows(rows, 1000, 400, imaging::Direction::kMinusY);
  EXPECT_EQ(minus_y_rows[0].x, 26);  // across +-y motion: the camera's columns
  EXPECT_EQ(minus_y_rows[0].width, 148);
  EXPECT_EQ(minus_y_rows[0].y, 400 - 324);
  // Margins stop at the frame's edges.
  const std::vector<LabelRegion> edge = {{0, 40, true}};
  const auto clipped = decode_windows(edge, 1000, 400, imaging::Direction::kPlusX);
  EXPECT_EQ(clipped[0].x, 0);
  EXPECT_EQ(clipped[0].width, 64);
}

TEST(BarcodeReader, SymbologyListsAreCheckedByName) {
  EXPECT_EQ(check_symbologies(kDefaultSymbologies), "");
  EXPECT_EQ(check_symbologies("Code128, QRCode"), "");
  EXPECT_NE(check_symbologies("Code128,Code129"), "");
  EXPECT_NE(check_symbologies(""), "");
}

TEST(BarcodeReader, ASymbologyIsNamedAsZXingParsesTheList) {
  EXPECT_TRUE(names_symbology("Code128,EAN-13", "EAN-13"));
  EXPECT_TRUE(names_symbology("Code128, ean13", "EAN-13"));
  EXPECT_TRUE(names_symbology("EAN13", "EAN-13"));
  EXPECT_FALSE(names_symbology("Code128,UPC-A", "EAN-13"));
  EXPECT_FALSE(names_symbology("EAN-8", "EAN-13"));
}

TEST(BarcodeReader, TheLinearSymbologiesOfAListAreAListOfTheirOwn) {
  const std::string linear = linear_symbologies("Code128,EAN-13,QRCode,DataMatrix");
  EXPECT_EQ(check_symbologies(linear), "") << linear;  // a list the reader takes
  EXPECT_NE(linear.find("Code128"), std::string::npos) << linear;
  EXPECT_NE(linear.find("EAN-13"), std::string::npos) << linear;
  EXPECT_EQ(linear.find("QR"), std::string::npos) << linear;
  EXPECT_EQ(linear.find("DataMatrix"), std::string::npos) << linear;
  EXPECT_EQ(linear_symbologies("QRCode, DataMatrix"), "");
}

TEST(BarcodeReader, OneSymbolReadOverDifferentRowsIsOneTwoAlikeSideBySideAreTwoTwoValuesAreNone) {
  // A linear code read on two latents: ZXing found it over rows 166-278 in one
  // and 205-278 in the other, so the centres lie 20 px apart across the bars.
  auto code = [](double x0, double x1, double y0, double y1) {
    DecodedCode c;
    c.text = "005-3379497200006";
    c.format = "Code128";
    c.quality.corners = {{{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}}};
    c.min_x = x0;
    c.max_x = x1;
    c.centre_x = (x0 + x1) / 2;
    c.centre_y = (y0 + y1) / 2;
    return c;
  };
  const DecodedCode tall = code(134, 634, 166, 278), short_rows = code(136, 631, 205, 278);
  EXPECT_TRUE(same_symbol(tall, short_rows));
  EXPECT_TRUE(same_symbol(short_rows, tall));
  // The same text printed twice, side by side or one above the other: two symbols.
  EXPECT_FALSE(same_symbol(tall, code(700, 1200, 166, 278)));
  EXPECT_FALSE(same_symbol(tall, code(134, 634, 300, 412)));
  // Another text at the same place: not the same symbol.
  DecodedCode other = short_rows;
  other.text = "005-3379497200007";
  EXPECT_FALSE(same_symbol(tall, other));
  // ...and one of the two a misread: neither is kept. A third code elsewhere
  // and another symbology's read of the same place (EAN-13 and UPC-A) stay.
  DecodedCode beside = code(700, 1200, 166, 278);
  DecodedCode upc = tall;
  upc.format = "UPC-A";
  upc.text = "05-3379497200006";
  std::vector<DecodedCode> codes = {tall, beside, other, upc};
  drop_conflicting(codes);
  ASSERT_EQ(codes.size(), 2u);
  EXPECT_EQ(codes[0].centre_x, beside.centre_x);
  EXPECT_EQ(codes[1].format, "UPC-A");
  // The same text twice over one place is one symbol, not a conflict.
  codes = {tall, short_rows};
  drop_conflicting(codes);
  EXPECT_EQ(codes.size(), 2u);
  // Another value read on the bars' rows just below (ZXing reports the lines
  // it read): over one place, both dropped. One printed 22 rows below: two symbols.
  DecodedCode band = code(136, 631, 270, 330), stacked = code(134, 634, 300, 412);
  band.text = stacked.text = "005-3379497200007";
  codes = {tall, band};
  drop_conflicting(codes);
  EXPECT_TRUE(codes.empty());
  codes = {tall, stacked};
  drop_conflicting(codes);
  EXPECT_EQ(codes.size(), 2u);
}

}  // namespace
}  // namespace flutterscan::reader
