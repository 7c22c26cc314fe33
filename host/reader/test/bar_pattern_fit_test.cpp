// A read's bars fitted to the picture: the value that is there explains every
// character; another value that passes the same check digit does not.
#include "reader/bar_pattern_fit.hpp"

#include <ZXing/BitMatrix.h>
#include <ZXing/MultiFormatWriter.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <string>
#include <vector>

#include "reader/barcode_reader.hpp"
#include "sim/scene.hpp"

namespace flutterscan::reader {
namespace {

imaging::Plane render(const std::string& scene, double module_px, double noise) {
  auto spec = sim::parse_scene(scene);
  EXPECT_TRUE(spec.ok()) << scene;
  spec.value().width = 480;
  spec.value().height = 240;
  spec.value().module_px = module_px;
  spec.value().print_blur_px = 1.0;
  auto image = sim::render_scene(spec.value());
  EXPECT_TRUE(image.ok()) << image.error();
  std::mt19937_64 rng(11);
  std::normal_distribution<float> normal(0.0f, static_cast<float>(noise));
  for (float& v : image.value().pixels) v += normal(rng);
  return std::move(image.value());
}

DecodedCode read_one(const imaging::Plane& image) {
  const BarcodeReadout readout = read_barcodes(image);
  EXPECT_EQ(readout.codes.size(), 1u);
  return readout.codes.empty() ? DecodedCode{} : readout.codes.front();
}

/// `digits` (one short of the symbol's) with their EAN/UPC check digit.
std::string with_check_digit(const std::string& digits) {
  int sum = 0;
  for (std::size_t i = 0; i < digits.size(); ++i) {
    const int d = digits[digits.size() - 1 - i] - '0';
    sum += i % 2 == 0 ? 3 * d : d;
  }
  return digits + static_cast<char>('0' + (10 - sum % 10) % 10);
}

TEST(BarPatternFit, TheValueReadExplainsEveryCharacterThroughNoise) {
  for (const double noise : {0.0, 0.1}) {
    const imaging::Plane image = render("ean13:590123412345", 2.5, 0.0);
    const imaging::Plane noisy = render("ean13:590123412345", 2.5, noise);
    const DecodedCode code = read_one(image);
    ASSERT_EQ(code.format, "EAN-13");
    const BarPatternFit fit = fit_bar_pattern(noisy, code);
    ASSERT_TRUE(fit.judged) << fit.problem;
    EXPECT_EQ(fit.characters, 12);
    EXPECT_GT(fit.worst_margin, 1.0) << "noise " << noise << ", character " << fit.worst_character;
    EXPECT_NEAR(fit.contrast, 0.8, 0.15);
  }
}

TEST(BarPatternFit, AnotherValueWithAValidCheckDigitIsToldApartAtTheCharactersItChanges) {
  const imaging::Plane image = render("ean13:590123412345", 2.5, 0.1);
  DecodedCode code = read_one(render("ean13:590123412345", 2.5, 0.0));
  ASSERT_EQ(code.format, "EAN-13");
  // The fourth digit (the third character of the left half) changed, the
  // check digit (the right half's last) with it.
  std::string other = code.text.substr(0, 12);
  other[3] = other[3] == '7' ? '2' : '7';
  code.text = with_check_digit(other);
  const BarPatternFit fit = fit_bar_pattern(image, code);
  ASSERT_TRUE(fit.judged) << fit.problem;
  EXPECT_LT(fit.worst_margin, 0.0);
  EXPECT_TRUE(fit.worst_character == 2 || fit.worst_character == 11) << fit.worst_character;
}

/// EAN-8 `value` drawn by ZXing's writer, 3 px per module, on white paper
/// (the simulator's scenes have no EAN-8).
imaging::Plane ean8(const std::string& value, double noise) {
  const ZXing::BitMatrix bits =
      ZXing::MultiFormatWriter(ZXing::BarcodeFormat::EAN8).setMargin(10).encode(value, 1, 1);
  constexpr int kModule = 3;
  imaging::Plane image(bits.width() * kModule, 90, 0.85f);
  std::mt19937_64 rng(5);
  std::normal_distribution<float> normal(0.0f, static_cast<float>(noise));
  for (int y = 15; y < 75; ++y)
    for (int x = 0; x < image.width; ++x)
      image.at(x, y) = (bits.get(x / kModule, 0) ? 0.1f : 0.85f) + normal(rng);
  return image;
}

TEST(BarPatternFit, AnEan8IsJudgedByItsOwnLayout) {
  const imaging::Plane image = ean8("96385074", 0.05);
  DecodedCode code = read_one(ean8("96385074", 0.0));
  ASSERT_EQ(code.format, "EAN-8");
  const BarPatternFit fit = fit_bar_pattern(image, code);
  ASSERT_TRUE(fit.judged) << fit.problem;
  EXPECT_EQ(fit.characters, 8);
  EXPECT_GT(fit.worst_margin, 1.0);
  code.text = with_check_digit("9638517");
  EXPECT_LT(fit_bar_pattern(image, code).worst_margin, 0.0);
}

TEST(BarPatternFit, WhatItCannotJudgeSaysWhy) {
  const imaging::Plane image = render("code128:FS-00042", 2.5, 0.0);
  const DecodedCode code128 = read_one(image);
  const BarPatternFit other_format = fit_bar_pattern(image, code128);
  EXPECT_FALSE(other_format.judged);
  EXPECT_NE(other_format.problem.find("Code128"), std::string::npos) << other_format.problem;

  DecodedCode ean = read_one(render("ean13:590123412345", 2.5, 0.0));
  DecodedCode off = ean;
  for (CodePoint& p : off.quality.corners) p.x += 400;
  const BarPatternFit off_latent = fit_bar_pattern(image, off);
  EXPECT_FALSE(off_latent.judged);
  EXPECT_NE(off_latent.problem.find("runs off"), std::string::npos) << off_latent.problem;

  ean.text = "5901234123458";  // a check digit that is not the value's
  const BarPatternFit refused = fit_bar_pattern(image, ean);
  EXPECT_FALSE(refused.judged);
  EXPECT_NE(refused.problem.find("writer refuses"), std::string::npos) << refused.problem;
}

/// Row `y` of `image`.
std::vector<double> row_of(const imaging::Plane& image, int y) {
  std::vector<double> r;
  for (int x = 0; x < image.width; ++x) r.push_back(image.at(x, y));
  return r;
}

TEST(ReadEan13ByFit, FindsAndReadsTheValueThroughNoiseEitherWayRound) {
  const imaging::Plane clean = render("ean13:590123412345", 2.5, 0.0);
  const DecodedCode truth = read_one(clean);
  const int y = static_cast<int>(truth.centre_y);
  // Where ZXing's corners put the first bar's edge and the last's.
  const CodeCorners& c = truth.quality.corners;
  const double first_bar = (c[0].x + c[3].x) / 2, last_bar = (c[1].x + c[2].x) / 2;
  // One row through noise a seventh of the bars' contrast, rms, searched
  // from 40 px before the bars to 40 px after them.
  const std::vector<double> noisy = row_of(render("ean13:590123412345", 2.5, 0.12), y);
  const FittedRead read = read_ean13_by_fit(noisy, first_bar - 40, last_bar + 40);
  EXPECT_EQ(read.text, truth.text) << read.problem;
  EXPECT_GE(read.worst_margin, kMinFittedReadMargin);
  EXPECT_NEAR(read.begin, first_bar, 1.5);
  EXPECT_NEAR(read.end, last_bar, 1.5);

  const std::vector<double> mirrored(noisy.rbegin(), noisy.rend());
  const double last = static_cast<double>(mirrored.size()) - 1;
  const FittedRead turned =
      read_ean13_by_fit(mirrored, last - last_bar - 40, last - first_bar + 40);
  EXPECT_EQ(turned.text, truth.text) << turned.problem;
  EXPECT_NEAR(turned.begin, last - first_bar, 1.5);  // read right to left
  EXPECT_NEAR(turned.end, last - last_bar, 1.5);
}

TEST(ReadEan13ByFit, NoiseAloneReadsNothing) {
  std::mt19937_64 rng(21);
  std::normal_distribution<double> normal(0.5, 0.2);
  for (int draw = 0; draw < 5; ++draw) {
    std::vector<double> samples(400);
    for (double& v : samples) v = normal(rng);
    const FittedRead read = read_ean13_by_fit(samples, 0, 400);
    EXPECT_TRUE(read.text.empty()) << read.text << " read from noise, margin " << read.worst_margin;
    EXPECT_FALSE(read.problem.empty());
  }
}

}  // namespace
}  // namespace flutterscan::reader
