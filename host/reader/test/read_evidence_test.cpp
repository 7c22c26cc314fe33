// What backs a value: a weak-check symbology's read counts only where a second
// reading agrees (read_evidence.hpp).
// ZXing 1.4 returns UTF-8 std::string from Result::text() only with ZX_USE_UTF8.
#define ZX_USE_UTF8 1

#include "reader/read_evidence.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include <ZXing/BitMatrix.h>
#include <ZXing/DecodeHints.h>
#include <ZXing/ImageView.h>
#include <ZXing/MultiFormatWriter.h>
#include <ZXing/ReadBarcode.h>

#include "reader/barcode_reader.hpp"
#include "sim/scene.hpp"

namespace flutterscan::reader {
namespace {

imaging::Plane rendered(const std::string& scene, int width, int height, double module_px) {
  auto spec = sim::parse_scene(scene);
  EXPECT_TRUE(spec.ok()) << spec.error();
  spec.value().width = width;
  spec.value().height = height;
  spec.value().module_px = module_px;
  auto plane = sim::render_scene(spec.value());
  EXPECT_TRUE(plane.ok()) << plane.error();
  return plane.value();
}

TEST(ReadEvidence, WeakChecksAreTheEanUpcFamilyItfCode39AndCodabar) {
  for (const char* weak : {"EAN-13", "EAN-8", "UPC-A", "UPC-E", "ITF", "Code39", "Codabar"})
    EXPECT_TRUE(weak_check(weak)) << weak;
  for (const char* strong : {"Code128", "Code93", "QRCode", "DataMatrix", "Aztec", "PDF417"})
    EXPECT_FALSE(weak_check(strong)) << strong;
  EXPECT_EQ(symbology_family("UPC-E"), symbology_family("EAN-13"));
  EXPECT_EQ(symbology_family("UPC-A"), symbology_family("EAN-8"));
  EXPECT_NE(symbology_family("Code39"), symbology_family("EAN-13"));
}

TEST(ReadEvidence, AnEan13ReadsOnBothHalvesOfItsBarsACode128IsBackedByItsCheck) {
  const imaging::Plane ean = rendered("ean13:590123412345", 480, 240, 2.5);
  const BarcodeReadout read = read_barcodes(ean);
  ASSERT_EQ(read.codes.size(), 1u);
  EXPECT_EQ(read.codes[0].text, "5901234123457");
  EXPECT_EQ(read.codes[0].evidence, "halves");
  EXPECT_TRUE(read.unconfirmed.empty());
  const BarcodeReadout code128 = read_barcodes(rendered("code128:PARCEL-0042", 480, 240, 2.5));
  ASSERT_EQ(code128.codes.size(), 1u);
  EXPECT_EQ(code128.codes[0].evidence, "check");
}

TEST(ReadEvidence, OnALatentWhosePriorTiesRowsTogetherOnlyASecondDecoderBacksAValue) {
  const imaging::Plane ean = rendered("ean13:590123412345", 480, 240, 2.5);
  DecodeWindow window{0, 0, ean.width, ean.height};
  window.independent_apart = 0;
  const BarcodeReadout read = read_barcodes(ean, kDefaultSymbologies, true, {&window, 1});
  ASSERT_EQ(read.codes.size(), 1u);
  EXPECT_EQ(read.codes[0].evidence, "decoders");
  const BarcodeReadout turned = read_barcodes_turned(ean, window, 0.01, kDefaultSymbologies, true);
  ASSERT_EQ(turned.codes.size(), 1u);
  EXPECT_EQ(turned.codes[0].evidence, "decoders");
}

TEST(ReadEvidence, AValueTheHalvesDoNotReadIsNotBacked) {
  // The label's bars, and a value they do not encode (its fifth digit 2 -> 9,
  // the check digit made to pass) said to lie where they are: neither half
  // nor zbar reads it.
  const imaging::Plane ean = rendered("ean13:590123412345", 480, 240, 2.5);
  const BarcodeReadout read = read_barcodes(ean);
  ASSERT_EQ(read.codes.size(), 1u);
  DecodedCode misread = read.codes[0];
  misread.text = "5901934123450";
  std::vector<std::uint8_t> lum(ean.pixels.size());
  for (std::size_t i = 0; i < lum.size(); ++i)
    lum[i] = static_cast<std::uint8_t>(std::clamp(ean.pixels[i], 0.0f, 1.0f) * 255 + 0.5f);
  ZXing::DecodeHints hints;
  hints.setFormats(ZXing::BarcodeFormat::LinearCodes).setTryHarder(true);
  const LumWindow window{lum, ean.width, ean.height, 0, 0, {}};
  EXPECT_EQ(corroboration(read.codes[0], window, hints, kDefaultSymbologies, true), "halves");
  EXPECT_EQ(corroboration(misread, window, hints, kDefaultSymbologies, true), "");
  // Cut across its bars at the symbol's centre: a symbol whose centre is said
  // to lie off the window has no halves, and zbar alone backs ZXing's value.
  DecodedCode off = read.codes[0];
  off.centre_y = -5;
  EXPECT_EQ(corroboration(off, window, hints, kDefaultSymbologies, true), "decoders");
}

TEST(ReadEvidence, ASymbologyWithNoCheckIsBackedByTheOtherDecoderNotByItsHalves) {
  // A clean Code 39 (no check character): both halves read it, as they read an
  // EAN-13; only zbar's reading backs it.
  const int width = 480, height = 240;
  const ZXing::BitMatrix bits = ZXing::MultiFormatWriter(ZXing::BarcodeFormat::Code39)
                                    .setMargin(20)
                                    .encode(L"PARCEL42", width, height);
  std::vector<std::uint8_t> lum(static_cast<std::size_t>(width) * height);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      lum[static_cast<std::size_t>(y) * width + x] = bits.get(x, y) ? 0 : 255;
  ZXing::DecodeHints hints;
  hints.setFormats(ZXing::BarcodeFormat::LinearCodes).setTryHarder(true);
  const ZXing::Results results = ZXing::ReadBarcodes(
      ZXing::ImageView(lum.data(), width, height, ZXing::ImageFormat::Lum), hints);
  ASSERT_EQ(results.size(), 1u);
  DecodedCode code;
  code.text = results[0].text();
  code.format = ZXing::ToString(results[0].format());
  code.decoder = "zxing";
  code.centre_x = width / 2.0;
  code.centre_y = height / 2.0;
  for (int i = 0; i < 4; ++i)  // where it lies, as read_barcodes() gives it
    code.quality.corners[static_cast<std::size_t>(i)] = {
        static_cast<double>(results[0].position()[i].x),
        static_cast<double>(results[0].position()[i].y)};
  code.min_x = std::min(code.quality.corners[0].x, code.quality.corners[3].x);
  code.max_x = std::max(code.quality.corners[1].x, code.quality.corners[2].x);
  ASSERT_EQ(code.format, "Code39");
  ASSERT_EQ(code.text, "PARCEL42");
  EXPECT_TRUE(no_check(code.format));
  const LumWindow window{lum, width, height, 0, 0, {}};
  EXPECT_EQ(corroboration(code, window, hints, kDefaultSymbologies, true), "decoders");
  // zbar told to read EAN-13 only: nothing backs the value, though both halves read it.
  EXPECT_EQ(corroboration(code, window, hints, "EAN-13", true), "");
  for (const char* checked : {"EAN-13", "UPC-E", "Code128"}) EXPECT_FALSE(no_check(checked));
}

/// `plane` as 8-bit luminance, clamped to [0, 1].
std::vector<std::uint8_t> luminance(const imaging::Plane& plane) {
  std::vector<std::uint8_t> lum;
  for (const float v : plane.pixels)
    lum.push_back(static_cast<std::uint8_t>(std::lround(255 * std::clamp(v, 0.0f, 1.0f))));
  return lum;
}

TEST(ReadEvidence, AHalfNoRowOfWhichReadsLeavesTheSecondDecoderAsTheOnlyBacking) {
  // The top quarter of the label drowned in noise (four times the bars'
  // contrast, rms) and the cut 30 rows down: no row of the top half reads;
  // zbar reads the clean rows.
  imaging::Plane ean = rendered("ean13:590123412345", 480, 240, 2.5);
  const BarcodeReadout clean = read_barcodes(ean);
  ASSERT_EQ(clean.codes.size(), 1u);
  DecodedCode code = clean.codes[0];
  code.centre_y = 30;
  std::mt19937_64 rng(7);
  std::normal_distribution<float> noise(0.0f, 4.0f);
  for (int y = 0; y < 60; ++y)
    for (int x = 0; x < ean.width; ++x) ean.at(x, y) += noise(rng);
  const std::vector<std::uint8_t> lum = luminance(ean);
  const LumWindow window{lum, ean.width, ean.height, 0, 0, {}};
  ZXing::DecodeHints hints;
  hints.setFormats(ZXing::BarcodeFormat::LinearCodes).setTryHarder(true);
  EXPECT_EQ(corroboration(code, window, hints, kDefaultSymbologies, true), "decoders");
  // The cut at the middle: each half has clean rows, and one that reads is enough.
  code.centre_y = 150;
  EXPECT_EQ(corroboration(code, window, hints, kDefaultSymbologies, true), "halves");
  // Neither where rows share samples across a gap wider than the clean half.
  EXPECT_EQ(corroboration(code, window, hints, kDefaultSymbologies, true, 2 * 150), "decoders");
}

TEST(ReadEvidence, OnlyTheSymbolsOwnSurroundingsBackIt) {
  // Two copies of one label side by side, the left one's bars drowned in noise
  // (four times their contrast, rms): a value said to lie on the left copy is
  // backed by neither its halves nor zbar there; the clean copy beside it, the
  // same value elsewhere in the window, is no evidence of this symbol.
  const imaging::Plane label = rendered("ean13:590123412345", 480, 240, 2.5);
  const BarcodeReadout clean = read_barcodes(label);
  ASSERT_EQ(clean.codes.size(), 1u);
  imaging::Plane pair(2 * label.width, label.height);
  std::mt19937_64 rng(11);
  std::normal_distribution<float> noise(0.0f, 4.0f);
  for (int y = 0; y < label.height; ++y)
    for (int x = 0; x < label.width; ++x) {
      pair.at(x, y) = label.at(x, y) + noise(rng);
      pair.at(x + label.width, y) = label.at(x, y);
    }
  const std::vector<std::uint8_t> lum = luminance(pair);
  const LumWindow window{lum, pair.width, pair.height, 0, 0, {}};
  ZXing::DecodeHints hints;
  hints.setFormats(ZXing::BarcodeFormat::LinearCodes).setTryHarder(true);
  EXPECT_EQ(corroboration(clean.codes[0], window, hints, kDefaultSymbologies, true), "");
  // The same value said to lie on the clean copy is backed there.
  DecodedCode right = clean.codes[0];
  right.centre_x += label.width;
  right.min_x += label.width;
  right.max_x += label.width;
  for (CodePoint& p : right.quality.corners) p.x += label.width;
  EXPECT_EQ(corroboration(right, window, hints, kDefaultSymbologies, true), "halves");
}

TEST(ReadEvidence, AnUpcEAndAnEan13OverOnePlaceConflict) {
  DecodedCode ean;
  ean.text = "5201815331227";
  ean.format = "EAN-13";
  ean.quality.corners = {{{100, 50}, {300, 50}, {300, 120}, {100, 120}}};
  ean.centre_x = 200;
  ean.centre_y = 85;
  DecodedCode upce = ean;
  upce.text = "12058754";
  upce.format = "UPC-E";
  upce.quality.corners = {{{150, 60}, {290, 60}, {290, 110}, {150, 110}}};
  std::vector<DecodedCode> codes = {ean, upce};
  drop_conflicting(codes);
  EXPECT_TRUE(codes.empty());
}

}  // namespace
}  // namespace flutterscan::reader
