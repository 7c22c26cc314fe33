#include "sim/scene.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <cstdio>
#include <filesystem>
#include <ostream>
#include <regex>
#include <string>
#include <utility>
#include <vector>

#include "reader/barcode_reader.hpp"

namespace flutterscan::sim {
namespace {

namespace fs = std::filesystem;

SceneSpec make_spec(SceneKind kind, const std::string& content) {
  SceneSpec spec;
  spec.kind = kind;
  spec.content = content;
  return spec;
}

/// Renders `spec`, failing the test (and returning an empty plane) on error.
imaging::Plane render_ok(const SceneSpec& spec) {
  auto result = render_scene(spec);
  EXPECT_TRUE(result.ok()) << result.error();
  if (!result.ok()) return {};
  EXPECT_EQ(result.value().width, spec.width);
  EXPECT_EQ(result.value().height, spec.height);
  return result.value();
}

/// The ink area of row y in pixels: each pixel's ink fraction, summed.
double ink_area_of_row(const imaging::Plane& image, int y, const SceneSpec& spec) {
  double area = 0;
  for (float v : image.row(y)) {
    if (v <= spec.paper) area += (spec.paper - v) / (spec.paper - spec.ink);
  }
  return area;
}

/// A directory of its own under the system temporary directory, removed at the end.
class ScratchDir {
 public:
  ScratchDir() : path_(fs::temp_directory_path() / ("scene_test_" + std::to_string(::getpid()))) {
    fs::create_directories(path_);
  }
  ~ScratchDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

struct BarcodeCase {
  SceneKind kind;
  std::string content;
};

void PrintTo(const BarcodeCase& c, std::ostream* os) {
  *os << scene_kind_name(c.kind) << ":" << c.content;
}

class BarcodeRoundTrip : public ::testing::TestWithParam<BarcodeCase> {};

TEST_P(BarcodeRoundTrip, RendersAndDecodesToItsContent) {
  const auto& param = GetParam();
  const imaging::Plane image = render_ok(make_spec(param.kind, param.content));
  ASSERT_FALSE(image.empty());
  EXPECT_EQ(reader::code_texts(reader::read_barcodes(image)),
            std::vector<std::string>{param.content});
}

TEST_P(BarcodeRoundTrip, FractionalModulesStillDecode) {
  const auto& param = GetParam();
  SceneSpec spec = make_spec(param.kind, param.content);
  spec.module_px = 2.5;
  const imaging::Plane image = render_ok(spec);
  ASSERT_FALSE(image.empty());
  EXPECT_EQ(reader::code_texts(reader::read_barcodes(image)),
            std::vector<std::string>{param.content});
}

INSTANTIATE_TEST_SUITE_P(
    Kinds, BarcodeRoundTrip,
    ::testing::Values(BarcodeCase{SceneKind::kCode128, "FLUTTER-0042"},
                      BarcodeCase{SceneKind::kEan13, "4006381333931"},
                      BarcodeCase{SceneKind::kQr, "https://example.com/flutterscan?id=42"},
                      BarcodeCase{SceneKind::kDataMatrix, "FLUTTERSCAN DM 0042"}),
    [](const ::testing::TestParamInfo<BarcodeCase>& param_info) {
      return std::string(scene_kind_name(param_info.param.kind));
    });

TEST(RenderScene, LabelLiesOnTheBeltWithPaperAndInkInItsMiddle) {
  const SceneSpec spec = make_spec(SceneKind::kCode128, "FLUTTER-0042");
  const imaging::Plane image = render_ok(spec);
  ASSERT_FALSE(image.empty());
  const float belt = static_cast<float>(spec.belt);
  EXPECT_EQ(image.at(0, 0), belt);
  EXPECT_EQ(image.at(image.width - 1, 0), belt);
  EXPECT_EQ(image.at(0, image.height - 1), belt);
  EXPECT_EQ(image.at(image.width - 1, image.height - 1), belt);
  int paper = 0, ink = 0;
  for (int y = image.height / 2 - 10; y < image.height / 2 + 10; ++y) {
    for (int x = image.width / 2 - 40; x < image.width / 2 + 40; ++x) {
      paper += image.at(x, y) == static_cast<float>(spec.paper);
      ink += image.at(x, y) == static_cast<float>(spec.ink);
    }
  }
  EXPECT_GT(paper, 100);
  EXPECT_GT(ink, 100);
}

TEST(RenderScene, WholePixelModulesGiveOnlyBeltPaperAndInk) {
  for (SceneKind kind : {SceneKind::kCode128, SceneKind::kQr}) {
    const SceneSpec spec = make_spec(kind, "FLUTTER-0042");
    const imaging::Plane image = render_ok(spec);
    int other = 0;
    for (float v : image.pixels) {
      other += v != static_cast<float>(spec.belt) && v != static_cast<float>(spec.paper) &&
               v != static_cast<float>(spec.ink);
    }
    EXPECT_EQ(other, 0) << scene_kind_name(kind);
  }
}

TEST(RenderScene, FractionalModulesAreAreaAveraged) {
  // The ink area of a bar row scales exactly with the module size, and edge
  // pixels of 2.5 px modules are partly covered.
  SceneSpec fine = make_spec(SceneKind::kCode128, "FLUTTER-0042");
  fine.width = 1200;
  fine.module_px = 2.5;
  fine.belt = fine.paper;  // so that only print counts as ink
  SceneSpec coarse = fine;
  coarse.module_px = 5;
  const imaging::Plane a = render_ok(fine);
  const imaging::Plane b = render_ok(coarse);
  ASSERT_FALSE(a.empty());
  ASSERT_FALSE(b.empty());
  const int y = fine.height / 2;
  EXPECT_NEAR(2 * ink_area_of_row(a, y, fine), ink_area_of_row(b, y, coarse), 1e-3);
  int partial = 0;
  for (float v : a.row(y))
    partial +=
        v > static_cast<float>(fine.ink) + 1e-3f && v < static_cast<float>(fine.paper) - 1e-3f;
  EXPECT_GT(partial, 10);
}

TEST(RenderScene, FlatSceneIsOneReflectance) {
  const auto spec = parse_scene("flat:0.85");
  ASSERT_TRUE(spec.ok()) << spec.error();
  const auto plane = render_scene(spec.value());
  ASSERT_TRUE(plane.ok()) << plane.error();
  EXPECT_EQ(plane.value().width, 640);
  for (float v : plane.value().pixels) ASSERT_FLOAT_EQ(v, 0.85f);
  for (const char* bad : {"flat:", "flat:white", "flat:1.5", "flat:0.5x"}) {
    const auto refused = parse_scene(bad);
    ASSERT_FALSE(refused.ok()) << bad;
    EXPECT_NE(refused.error().find("flat"), std::string::npos) << refused.error();
  }
}

TEST(RenderScene, TextSceneHasInkOnPaper) {
  const SceneSpec spec = make_spec(SceneKind::kText, "HELLO BELT 42");
  const imaging::Plane image = render_ok(spec);
  ASSERT_FALSE(image.empty());
  EXPECT_EQ(image.at(0, 0), static_cast<float>(spec.belt));
  int ink = 0, paper = 0;
  for (float v : image.pixels) {
    ink += v < spec.ink + 0.1 * (spec.paper - spec.ink);
    paper += v == static_cast<float>(spec.paper);
  }
  EXPECT_GT(ink, 50);
  EXPECT_GT(paper, 1000);
}

TEST(RenderScene, ImageSceneIsLinearLuminance) {
  ScratchDir dir;
  const fs::path grey_path = dir.path() / "grey188.png";
  ASSERT_TRUE(cv::imwrite(grey_path.string(), cv::Mat(30, 40, CV_8UC1, cv::Scalar(188))));
  SceneSpec spec = make_spec(SceneKind::kImage, grey_path.string());
  spec.width = 20;  // shrink
  spec.height = 15;
  const imaging::Plane grey = render_ok(spec);
  ASSERT_FALSE(grey.empty());
  for (float v : grey.pixels) ASSERT_NEAR(v, 0.5029, 0.001);  // sRGB 188 in linear light

  const fs::path red_path = dir.path() / "red.png";
  ASSERT_TRUE(cv::imwrite(red_path.string(), cv::Mat(30, 40, CV_8UC3, cv::Scalar(0, 0, 255))));
  spec.content = red_path.string();
  spec.width = 64;  // enlarge
  spec.height = 48;
  const imaging::Plane red = render_ok(spec);
  ASSERT_FALSE(red.empty());
  for (float v : red.pixels) ASSERT_NEAR(v, 0.2126, 0.0005);  // Rec. 709 weight of red
}

TEST(RenderScene, UnreadableImageIsAnError) {
  const auto missing = render_scene(make_spec(SceneKind::kImage, "/nonexistent/label.png"));
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.error().find("/nonexistent/label.png"), std::string::npos) << missing.error();

  ScratchDir dir;
  const fs::path junk = dir.path() / "junk.png";
  {
    std::FILE* f = std::fopen(junk.c_str(), "w");
    ASSERT_NE(f, nullptr);
    std::fputs("not a picture", f);
    std::fclose(f);
  }
  const auto bad = render_scene(make_spec(SceneKind::kImage, junk.string()));
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().find("junk.png"), std::string::npos) << bad.error();
}

/// The size an error message says is needed, as {width, height}.
std::pair<int, int> needed_size(const std::string& message) {
  std::smatch match;
  const std::regex pattern(R"(at least (\d+) px wide and (\d+) px high)");
  if (!std::regex_search(message, match, pattern)) return {-1, -1};
  return {std::stoi(match[1]), std::stoi(match[2])};
}

TEST(RenderScene, TooSmallImageSaysTheWidthNeeded) {
  SceneSpec spec = make_spec(SceneKind::kCode128, "FLUTTER-0042");
  spec.width = 200;
  const auto small = render_scene(spec);
  ASSERT_FALSE(small.ok());
  const auto [need_w, need_h] = needed_size(small.error());
  ASSERT_GT(need_w, 200) << small.error();
  EXPECT_LE(need_h, spec.height) << small.error();
  spec.width = need_w;
  const imaging::Plane fits = render_ok(spec);
  ASSERT_FALSE(fits.empty());
  for (int x : {0, kMinBeltPx - 1, need_w - kMinBeltPx, need_w - 1}) {
    EXPECT_EQ(fits.at(x, spec.height / 2), static_cast<float>(spec.belt)) << "x = " << x;
  }
  spec.width = need_w - 1;
  EXPECT_FALSE(render_scene(spec).ok());
}

TEST(RenderScene, TooShortImageSaysTheHeightNeeded) {
  SceneSpec spec = make_spec(SceneKind::kQr, "FLUTTER-0042");
  spec.height = 60;
  const auto small = render_scene(spec);
  ASSERT_FALSE(small.ok());
  const auto [need_w, need_h] = needed_size(small.error());
  ASSERT_GT(need_h, 60) << small.error();
  spec.height = need_h;
  EXPECT_TRUE(render_scene(spec).ok());
  spec.height = need_h - 1;
  EXPECT_FALSE(render_scene(spec).ok());
}

TEST(RenderScene, ContentTheEncoderRejectsIsAnError) {
  const auto too_long = render_scene(make_spec(SceneKind::kQr, std::string(5000, 'A')));
  ASSERT_FALSE(too_long.ok());
  EXPECT_NE(too_long.error().find("qr cannot encode"), std::string::npos) << too_long.error();

  const auto bad_ean = render_scene(make_spec(SceneKind::kEan13, "12345"));
  ASSERT_FALSE(bad_ean.ok());
  EXPECT_NE(bad_ean.error().find("12 or 13 digits"), std::string::npos) << bad_ean.error();
}

TEST(RenderScene, RejectsBadSizesAndReflectances) {
  SceneSpec spec = make_spec(SceneKind::kCode128, "X");
  spec.module_px = 0;
  EXPECT_FALSE(render_scene(spec).ok());
  spec.module_px = 3;
  spec.paper = 1.5;
  EXPECT_FALSE(render_scene(spec).ok());
  spec.paper = 0.9;
  spec.width = 0;
  EXPECT_FALSE(render_scene(spec).ok());
}

TEST(DecodeBarcodes, FindsNothingInABlankImage) {
  EXPECT_TRUE(reader::read_barcodes(imaging::Plane(200, 100, 0.5f)).codes.empty());
  EXPECT_TRUE(reader::read_barcodes(imaging::Plane()).codes.empty());
}

TEST(ParseScene, ReadsEachKind) {
  const auto code = parse_scene("code128:FLUTTER-0042");
  ASSERT_TRUE(code.ok()) << code.error();
  EXPECT_EQ(code.value().kind, SceneKind::kCode128);
  EXPECT_EQ(code.value().content, "FLUTTER-0042");
  EXPECT_EQ(code.value().width, 640);
  EXPECT_EQ(code.value().module_px, 3);

  const auto qr = parse_scene("qr:https://example.com/a:b");
  ASSERT_TRUE(qr.ok()) << qr.error();
  EXPECT_EQ(qr.value().kind, SceneKind::kQr);
  EXPECT_EQ(qr.value().content, "https://example.com/a:b");

  EXPECT_EQ(parse_scene("ean13:400638133393").value().kind, SceneKind::kEan13);
  EXPECT_EQ(parse_scene("ean13:4006381333931").value().kind, SceneKind::kEan13);
  EXPECT_EQ(parse_scene("DataMatrix:X").value().kind, SceneKind::kDataMatrix);
  EXPECT_EQ(parse_scene("text:HELLO BELT").value().kind, SceneKind::kText);
  EXPECT_EQ(parse_scene("image:/tmp/label.png").value().content, "/tmp/label.png");
}

TEST(ParseScene, NamesTheProblem) {
  const auto expect_error = [](const std::string& text, const std::string& needle) {
    const auto result = parse_scene(text);
    ASSERT_FALSE(result.ok()) << text;
    EXPECT_NE(result.error().find(needle), std::string::npos) << text << " -> " << result.error();
  };
  expect_error("foo:bar", "unknown scene kind 'foo'; the kinds are code128, ean13, qr");
  expect_error("foo:bar", "image");
  expect_error("code128", "KIND:CONTENT");
  expect_error("qr:", "qr scene has no content");
  expect_error("text:", "no content");
  expect_error("ean13:12345", "ean13 needs 12 or 13 digits");
  expect_error("ean13:40063813339X", "digits only");
  expect_error("ean13:4006381333932", "check digit of '4006381333932' should be 1");
  expect_error("code128:caf\xc3\xa9", "printable ASCII");
}

// The sim camera's EAN-13 labels and the scene parser share this check digit.
TEST(Scene, Ean13CheckDigitWeighsTheFirstTwelveDigits) {
  EXPECT_EQ(ean13_check_digit("400638133393"), 1);
  EXPECT_EQ(ean13_check_digit("4006381333931"), 1);  // the 13th is not read
  EXPECT_EQ(ean13_check_digit("978020137962"), 4);
  EXPECT_EQ(ean13_check_digit("000000000000"), 0);
}

}  // namespace
}  // namespace flutterscan::sim

namespace flutterscan::sim {
namespace {

TEST(RenderScene, WeatheredPrintStillDecodesAndIsDeterministic) {
  auto spec = parse_scene("code128:FLUTTER-0042").value();
  const imaging::Plane exact = render_scene(spec).value();
  spec.print_blur_px = 0.6;
  spec.texture = 0.02;
  const imaging::Plane weathered = render_scene(spec).value();
  EXPECT_EQ(render_scene(spec).value().pixels, weathered.pixels);
  EXPECT_NE(weathered.pixels, exact.pixels);
  // Ink spread leaves grey edge pixels that the exact label does not have.
  const auto greys = std::count_if(weathered.pixels.begin(), weathered.pixels.end(), [](float v) {
    return v > 0.2f && v < 0.7f && std::abs(v - 0.35f) > 0.05f;
  });
  EXPECT_GT(greys, 1000);
  const auto decoded = reader::code_texts(reader::read_barcodes(weathered));
  ASSERT_EQ(decoded.size(), 1U);
  EXPECT_EQ(decoded[0], "FLUTTER-0042");
  spec.texture_seed = 2;
  EXPECT_NE(render_scene(spec).value().pixels, weathered.pixels);
}

TEST(RenderScene, WeatheringOutOfRangeIsRefused) {
  auto spec = parse_scene("code128:X").value();
  spec.print_blur_px = -1;
  EXPECT_NE(render_scene(spec).error().find("print blur"), std::string::npos);
  spec.print_blur_px = 0;
  spec.texture = 0.9;
  EXPECT_NE(render_scene(spec).error().find("texture"), std::string::npos);
}

}  // namespace
}  // namespace flutterscan::sim
