// Reading with the options bundle: the session's defaults (label paper only),
// the whole frame when a caller says so, and the windows found along the
// motion whatever its direction.
#include "reader/code_reading.hpp"

#include <ZXing/BitMatrix.h>
#include <ZXing/MultiFormatWriter.h>
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "imaging/motion_frame.hpp"

namespace flutterscan::reader {
namespace {

/// A 900 x 200 belt (0.35) with one Code 128 "FS-READ" (`code_height` rows tall) at column
/// `start`: on white label paper (0.9), or printed straight on the belt when `on_paper` is false.
imaging::Plane belt_with_code(int start, bool on_paper, const wchar_t* text = L"FS-READ",
                              int code_height = 120) {
  imaging::Plane belt(900, 200, 0.35f);
  const ZXing::BitMatrix bars = ZXing::MultiFormatWriter(ZXing::BarcodeFormat::Code128)
                                    .setMargin(10)
                                    .encode(text, 300, code_height);
  const float ground = on_paper ? 0.9f : 0.35f;
  for (int y = 0; y < 160; ++y)
    for (int x = 0; x < 320; ++x) {
      const int bx = x - 10, by = y - 20;
      const bool bar =
          bx >= 0 && by >= 0 && bx < bars.width() && by < bars.height() && bars.get(bx, by);
      belt.at(start + x, 20 + y) = bar ? 0.02f : ground;
    }
  return belt;
}

TEST(CodeReading, TheDefaultsAreTheSessionsAndTheWholeFrameDiffersOnlyInArea) {
  const ReaderOptions session;
  EXPECT_EQ(session.symbologies, kDefaultSymbologies);
  EXPECT_TRUE(session.try_rotate);
  EXPECT_EQ(session.area, DecodeArea::kLabels);
  const ReaderOptions whole = whole_frame_options();
  EXPECT_EQ(whole.symbologies, session.symbologies);
  EXPECT_EQ(whole.try_rotate, session.try_rotate);
  EXPECT_EQ(whole.area, DecodeArea::kFrame);
}

// A label cut by the frame's edge is read in options.cut_window_views: the
// session's line, which sees it whole in another frame, in the linear view only.
TEST(CodeReading, AWindowCutByTheFramesEdgeIsReadInTheViewsTheOptionsGiveIt) {
  imaging::Plane belt = belt_with_code(300, true);
  for (float& v : belt.pixels) v *= 0.05f;  // dark print on dark card: the sRGB view reads it
  LabelRegion region{280, 640, false, 10, 190};
  ReaderOptions options;
  EXPECT_EQ(options.cut_window_views, kLuminanceViews);
  const std::vector<std::string> read{"FS-READ"};
  EXPECT_EQ(code_texts(read_codes(belt, {&region, 1}, imaging::Direction::kPlusX, options).readout),
            read);
  options.cut_window_views = 1;  // whole: all the views still
  EXPECT_EQ(code_texts(read_codes(belt, {&region, 1}, imaging::Direction::kPlusX, options).readout),
            read);
  region.cut = true;
  EXPECT_TRUE(
      read_codes(belt, {&region, 1}, imaging::Direction::kPlusX, options).readout.codes.empty());
  options.cut_window_views = kLuminanceViews;
  EXPECT_EQ(code_texts(read_codes(belt, {&region, 1}, imaging::Direction::kPlusX, options).readout),
            read);
}

// A tile of a region cut to the budget looks for linear codes on every
// kTileRowStep-th row: a code 6 rows tall (one of them looked at, two needed),
// read in its region, is not in a tile.
TEST(CodeReading, ATilesWindowLooksForLinearCodesOnEveryEighthRow) {
  const imaging::Plane belt = belt_with_code(300, true, L"FS-LOW", 6);
  LabelRegion region{280, 640, false, 10, 190};
  ReaderOptions options;
  options.second_decoder = false;  // ZXing's scan alone
  EXPECT_EQ(code_texts(read_codes(belt, {&region, 1}, imaging::Direction::kPlusX, options).readout),
            std::vector<std::string>{"FS-LOW"});
  region.tile = true;
  EXPECT_TRUE(
      read_codes(belt, {&region, 1}, imaging::Direction::kPlusX, options).readout.codes.empty());
}

TEST(CodeReading, OnlyTheWholeFrameReadsACodeWithoutPaper) {
  const imaging::Plane belt = belt_with_code(300, false);
  const auto paper = find_paper_runs(belt);
  EXPECT_TRUE(paper.empty());
  const CodeReading labels = read_codes(belt, paper, imaging::Direction::kPlusX, ReaderOptions{});
  ASSERT_TRUE(labels.windows);
  EXPECT_EQ(*labels.windows, 0u);
  EXPECT_TRUE(labels.readout.codes.empty());
  const CodeReading frame =
      read_codes(belt, paper, imaging::Direction::kPlusX, whole_frame_options());
  EXPECT_FALSE(frame.windows);
  EXPECT_EQ(code_texts(frame.readout), std::vector<std::string>{"FS-READ"});
}

TEST(CodeReading, LabelWindowsFollowTheMotionAndKeepTheFramesPositions) {
  // The label at column 100 of a -x frame: 100 + 320 .. from the right in the motion frame.
  const imaging::Plane camera = belt_with_code(100, true);
  const imaging::Direction d = imaging::Direction::kMinusX;
  const auto paper = find_paper_runs(imaging::to_motion_frame(camera, d));
  ASSERT_EQ(paper.size(), 1u);
  const CodeReading labels = read_codes(camera, paper, d, ReaderOptions{});
  ASSERT_TRUE(labels.windows);
  EXPECT_EQ(*labels.windows, 1u);
  ASSERT_EQ(code_texts(labels.readout), std::vector<std::string>{"FS-READ"});
  const CodeReading frame = read_codes(camera, paper, d, whole_frame_options());
  ASSERT_EQ(frame.readout.codes.size(), 1u);
  EXPECT_NEAR(labels.readout.codes[0].centre_x, frame.readout.codes[0].centre_x, 1.0);
  EXPECT_LT(labels.readout.codes[0].centre_x, 450);  // the camera's column, not the motion frame's
}

// A second window mostly inside one that read a code is not decoded again; one
// beside it, or one reaching well beyond it (both codes), is.
TEST(CodeReading, AWindowMostlyInsideOneThatReadACodeIsSkipped) {
  imaging::Plane belt = belt_with_code(60, true);
  // (Another text: two equal symbols in one window are the next test's.)
  const imaging::Plane other = belt_with_code(540, true, L"FS-NEXT");
  for (int y = 0; y < belt.height; ++y)
    for (int x = 500; x < belt.width; ++x) belt.at(x, y) = other.at(x, y);
  const DecodeWindow first{0, 0, 450, 200}, around_first{20, 10, 400, 190},
      second{480, 0, 420, 200};
  const std::vector<DecodeWindow> windows{first, around_first, second};
  const BarcodeReadout readout = read_barcodes(belt, kDefaultSymbologies, true, windows);
  EXPECT_EQ(code_texts(readout), (std::vector<std::string>{"FS-READ", "FS-NEXT"}));
  EXPECT_EQ(readout.windows_skipped, 1u);
  // The first label read, then a window over both: half of it new, so read (the second label).
  const DecodeWindow both{0, 0, 900, 200};
  const std::vector<DecodeWindow> wider{first, both};
  const BarcodeReadout again = read_barcodes(belt, kDefaultSymbologies, true, wider);
  EXPECT_EQ(again.windows_skipped, 0u);
  EXPECT_EQ(code_texts(again), (std::vector<std::string>{"FS-READ", "FS-NEXT"}))
      << again.decoder_fault;
}

// A label that carries its barcode twice: two equal Code 128 symbols in one
// window fail an assertion in Debian's ZXing 1.4 (Result::operator==, comparing
// them); the window is read once more up to its first symbol, and its code read.
TEST(CodeReading, AWindowWithTheSameBarcodeTwiceReadsIt) {
  imaging::Plane belt = belt_with_code(60, true);
  const imaging::Plane again = belt_with_code(540, true);
  for (int y = 0; y < belt.height; ++y)
    for (int x = 500; x < belt.width; ++x) belt.at(x, y) = again.at(x, y);
  const DecodeWindow both{0, 0, belt.width, belt.height};
  const BarcodeReadout readout = read_barcodes(belt, "Code128", false, {&both, 1});
  EXPECT_EQ(readout.decoder_fault, "");
  EXPECT_EQ(code_texts(readout), std::vector<std::string>{"FS-READ"});
}

}  // namespace
}  // namespace flutterscan::reader
