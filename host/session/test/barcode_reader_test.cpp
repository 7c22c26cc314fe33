// The barcode reader survives ZXing's own assertions: Debian builds ZXing with
// assert() on, and its Micro QR sampler fails one on some deblurred frames.
#include "session/barcode_reader.hpp"

#include <ZXing/BitMatrix.h>
#include <ZXing/MultiFormatWriter.h>
#include <gtest/gtest.h>

#include <fstream>
#include <string>
#include <thread>

#include "session/assertion_guard.hpp"

// glibc's assertion handler, which assert() calls (not declared under NDEBUG).
extern "C" [[noreturn]] void __assert_fail(const char* assertion, const char* file,
                                           unsigned int line, const char* function) noexcept;

namespace flutterscan::session {
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

TEST(BarcodeReader, AnImageThatTripsZXingsMicroQrAssertionIsReportedNotFatal) {
  // A crop of a deblurred 1080p sim frame on which ZXing 1.4's Micro QR
  // sampler (FindConcentricPatternCorners -> intersect) aborted a session.
  const imaging::Plane image =
      read_pgm(FLUTTERSCAN_SOURCE_DIR "/host/session/test/data/zxing_micro_qr_assertion.pgm");
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

TEST(BarcodeReader, SymbologyListsAreCheckedByName) {
  EXPECT_EQ(check_symbologies(kDefaultSymbologies), "");
  EXPECT_EQ(check_symbologies("Code128, QRCode"), "");
  EXPECT_NE(check_symbologies("Code128,Code129"), "");
  EXPECT_NE(check_symbologies(""), "");
}

}  // namespace
}  // namespace flutterscan::session
