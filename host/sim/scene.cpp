#include "sim/scene.hpp"

#include <ZXing/BarcodeFormat.h>
#include <ZXing/BitMatrix.h>
#include <ZXing/CharacterSet.h>
#include <ZXing/MultiFormatWriter.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <random>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "sim/colour_scene.hpp"
#include "sim/photo_scene.hpp"

namespace flutterscan::sim {
namespace {

using PlaneResult = Result<imaging::Plane, std::string>;

struct KindName {
  SceneKind kind;
  std::string_view name;
};

constexpr std::array<KindName, 8> kKindNames{{
    {SceneKind::kCode128, "code128"},
    {SceneKind::kEan13, "ean13"},
    {SceneKind::kQr, "qr"},
    {SceneKind::kDataMatrix, "datamatrix"},
    {SceneKind::kText, "text"},
    {SceneKind::kImage, "image"},
    {SceneKind::kFlat, "flat"},
    {SceneKind::kPhoto, "photo"},
}};

constexpr int kMaxImageSide = 1 << 15;

// Quiet zones in modules (ISO/IEC 15417 asks 10 for Code 128; EAN-13 needs 11
// on the left and 7 on the right, given 11 both sides for a centred symbol).
constexpr double kCode128QuietModules = 10;
constexpr double kEan13QuietModules = 11;
constexpr double kLinearVerticalQuietModules = 5;
constexpr double kQrQuietModules = 4;
constexpr double kDataMatrixQuietModules = 2;
// Linear bar height as a fraction of the symbol's width: wanted, and least.
constexpr double kBarHeightWanted = 0.30;
constexpr double kBarHeightLeast = 0.15;
// Text: cap height and stroke in modules, paper around the text in modules,
// and the supersampling factor of the rendering.
constexpr double kTextCapModules = 7;
constexpr double kTextStrokeModules = 0.8;
constexpr double kTextMarginModules = 4;
constexpr int kTextSupersample = 4;

std::string kind_list() {
  std::string list;
  for (const KindName& k : kKindNames) {
    if (!list.empty()) list += ", ";
    list += k.name;
  }
  return list;
}

/// `value` as printf's %g writes it (3, 2.5, 0.35).
std::string format_number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", value);
  return text;
}

std::string to_lower(std::string text) {
  for (char& c : text) {
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  }
  return text;
}

bool is_ascii(const std::string& text) {
  return std::all_of(text.begin(), text.end(),
                     [](char c) { return static_cast<unsigned char>(c) < 0x80; });
}

/// The index of the first character that is not printable ASCII, or npos.
std::size_t first_unprintable(const std::string& text) {
  for (std::size_t i = 0; i < text.size(); ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c < 0x20 || c > 0x7e) return i;
  }
  return std::string::npos;
}

/// Problem with `content` for a scene of `kind` (empty if none).
std::string content_problem(SceneKind kind, const std::string& content) {
  const std::string name(scene_kind_name(kind));
  if (content.empty()) {
    return name + " scene has no content: write " + name + ":" +
           (kind == SceneKind::kImage || kind == SceneKind::kPhoto ? "PATH" : "TEXT");
  }
  switch (kind) {
    case SceneKind::kEan13: {
      for (char c : content) {
        if (c < '0' || c > '9') {
          return "ean13 takes digits only; '" + content + "' has '" + std::string(1, c) + "'";
        }
      }
      if (content.size() != 12 && content.size() != 13) {
        return "ean13 needs 12 or 13 digits (the 13th is the check digit); '" + content + "' has " +
               std::to_string(content.size());
      }
      if (content.size() == 13) {
        const int check = ean13_check_digit(content);
        if (content[12] - '0' != check) {
          return "ean13 check digit of '" + content + "' should be " + std::to_string(check) +
                 ", not " + content[12];
        }
      }
      return {};
    }
    case SceneKind::kCode128:
    case SceneKind::kText: {
      const std::size_t bad = first_unprintable(content);
      if (bad != std::string::npos) {
        return name + " takes printable ASCII only; character " + std::to_string(bad + 1) +
               " of '" + content + "' is not";
      }
      return {};
    }
    case SceneKind::kFlat: {
      char* end = nullptr;
      const double value = std::strtod(content.c_str(), &end);
      if (end == content.c_str() || *end != '\0' || !(value >= 0.0 && value <= 1.0))
        return "flat takes a reflectance from 0 to 1 (flat:0.9 for a white target), not '" +
               content + "'";
      return {};
    }
    case SceneKind::kQr:
    case SceneKind::kDataMatrix:
    case SceneKind::kImage:
    case SceneKind::kPhoto:
      return {};
  }
  return {};
}

std::string spec_problem(const SceneSpec& spec) {
  if (spec.width < 1 || spec.height < 1 || spec.width > kMaxImageSide ||
      spec.height > kMaxImageSide) {
    return "scene size " + std::to_string(spec.width) + " x " + std::to_string(spec.height) +
           " px is outside 1.." + std::to_string(kMaxImageSide);
  }
  if (spec.kind != SceneKind::kImage && spec.kind != SceneKind::kPhoto &&
      !(std::isfinite(spec.module_px) && spec.module_px > 0)) {
    return "module size " + format_number(spec.module_px) + " px is not a positive number";
  }
  const std::array<std::pair<const char*, double>, 3> reflectances{
      {{"paper", spec.paper}, {"ink", spec.ink}, {"belt", spec.belt}}};
  for (const auto& [what, value] : reflectances) {
    if (!(value >= 0.0 && value <= 1.0)) {
      return std::string(what) + " reflectance " + format_number(value) + " is outside 0..1";
    }
  }
  if (!(spec.print_blur_px >= 0.0 && spec.print_blur_px <= 10.0))
    return "print blur " + format_number(spec.print_blur_px) + " px is outside 0..10";
  if (!(spec.texture >= 0.0 && spec.texture <= 0.5))
    return "print texture " + format_number(spec.texture) + " is outside 0..0.5";
  return {};
}

/// Ink spread and paper texture over a label rendered `k` times finer than the
/// camera's pixels (SceneSpec::print_blur_px, ::texture, both in camera pixels):
/// the texture varies from camera pixel to camera pixel.
imaging::Plane weather_print(imaging::Plane plane, const SceneSpec& spec, int k) {
  if (spec.print_blur_px > 0) {
    cv::Mat view(plane.height, plane.width, CV_32F, plane.pixels.data());
    const double sigma = spec.print_blur_px * k;
    cv::GaussianBlur(view, view, cv::Size(0, 0), sigma, sigma, cv::BORDER_REPLICATE);
  }
  if (spec.texture > 0) {
    std::mt19937_64 rng(spec.texture_seed);
    std::normal_distribution<float> normal(0.0f, 1.0f);
    const auto texture = static_cast<float>(spec.texture);
    for (int y = 0; y < plane.height / k; ++y)
      for (int x = 0; x < plane.width / k; ++x) {
        const float factor = 1.0f + texture * normal(rng);
        for (int dy = 0; dy < k; ++dy)
          for (int dx = 0; dx < k; ++dx) {
            float& v = plane.at(x * k + dx, y * k + dy);
            v = std::clamp(v * factor, 0.0f, 1.0f);
          }
      }
  }
  return plane;
}

/// A barcode's modules, one cell per module (dark = ink), row-major.
struct ModuleGrid {
  int cols = 0;
  int rows = 0;
  std::vector<unsigned char> dark;
  bool at(int c, int r) const { return dark[static_cast<std::size_t>(r) * cols + c] != 0; }
};

Result<ModuleGrid, std::string> encode_symbol(SceneKind kind, const std::string& content) {
  using GridResult = Result<ModuleGrid, std::string>;
  ZXing::BarcodeFormat format = ZXing::BarcodeFormat::None;
  switch (kind) {
    case SceneKind::kCode128:
      format = ZXing::BarcodeFormat::Code128;
      break;
    case SceneKind::kEan13:
      format = ZXing::BarcodeFormat::EAN13;
      break;
    case SceneKind::kQr:
      format = ZXing::BarcodeFormat::QRCode;
      break;
    case SceneKind::kDataMatrix:
      format = ZXing::BarcodeFormat::DataMatrix;
      break;
    case SceneKind::kText:
    case SceneKind::kImage:
    case SceneKind::kFlat:
    case SceneKind::kPhoto:
      return GridResult::failure("not a barcode scene");
  }
  const std::string name(scene_kind_name(kind));
  try {
    ZXing::MultiFormatWriter writer(format);
    // No quiet zone (we draw our own) and a requested size of 0 x 0: the
    // writers then return one bit per module (1-D codes: a single row).
    writer.setMargin(0);
    if (!is_ascii(content)) writer.setEncoding(ZXing::CharacterSet::UTF8);
    const ZXing::BitMatrix bits = writer.encode(content, 0, 0);
    // Crop to the dark modules' bounding box in case a writer pads anyway;
    // every symbol here has dark modules on all four edges.
    int left = bits.width(), right = -1, top = bits.height(), bottom = -1;
    for (int y = 0; y < bits.height(); ++y) {
      for (int x = 0; x < bits.width(); ++x) {
        if (!bits.get(x, y)) continue;
        left = std::min(left, x);
        right = std::max(right, x);
        top = std::min(top, y);
        bottom = std::max(bottom, y);
      }
    }
    if (right < 0) return GridResult::failure(name + " encoder gave an empty symbol");
    ModuleGrid grid;
    grid.cols = right - left + 1;
    grid.rows = bottom - top + 1;
    grid.dark.resize(static_cast<std::size_t>(grid.cols) * grid.rows);
    for (int r = 0; r < grid.rows; ++r) {
      for (int c = 0; c < grid.cols; ++c) {
        grid.dark[static_cast<std::size_t>(r) * grid.cols + c] =
            bits.get(left + c, top + r) ? 1 : 0;
      }
    }
    return GridResult::success(std::move(grid));
  } catch (const std::exception& e) {
    return GridResult::failure(name + " cannot encode '" + content + "': " + e.what());
  }
}

/// Integer rectangle of the label in the image.
struct LabelRect {
  int x = 0, y = 0, w = 0, h = 0;
};

/// The label rectangle centred in the image, or an error naming the size needed.
Result<LabelRect, std::string> place_label(const SceneSpec& spec, int label_w, int label_h,
                                           const std::string& what) {
  const int need_w = label_w + 2 * kMinBeltPx;
  const int need_h = label_h + 2 * kMinBeltPx;
  if (need_w > spec.width || need_h > spec.height) {
    return Result<LabelRect, std::string>::failure(
        what + " needs an image at least " + std::to_string(need_w) + " px wide and " +
        std::to_string(need_h) + " px high (a " + std::to_string(label_w) + " x " +
        std::to_string(label_h) + " px label and " + std::to_string(kMinBeltPx) +
        " px of belt each side); the image is " + std::to_string(spec.width) + " x " +
        std::to_string(spec.height) + " px");
  }
  return Result<LabelRect, std::string>::success(
      {(spec.width - label_w) / 2, (spec.height - label_h) / 2, label_w, label_h});
}

std::string describe(const SceneSpec& spec) {
  return std::string(scene_kind_name(spec.kind)) + " '" + spec.content + "' at " +
         format_number(spec.module_px) + " px modules";
}

/// Whole pixels that hold `length` px (tolerating rounding error of sums).
int whole_px(double length) {
  return static_cast<int>(std::ceil(length - 1e-9));
}

/// For each pixel p in [first, first + count): the cells i (of `cells`, cell i
/// covering [origin + i*size, origin + (i+1)*size)) that overlap [p, p+1), with
/// the length of the overlap.
std::vector<std::vector<std::pair<int, double>>> cell_overlaps(double origin, double size,
                                                               int cells, int first, int count) {
  std::vector<std::vector<std::pair<int, double>>> overlaps(static_cast<std::size_t>(count));
  for (int k = 0; k < count; ++k) {
    const double lo = first + k;
    const double hi = lo + 1.0;
    const int i0 = std::max(0, static_cast<int>(std::floor((lo - origin) / size)));
    const int i1 = std::min(cells - 1, static_cast<int>(std::floor((hi - origin) / size)));
    for (int i = i0; i <= i1; ++i) {
      const double overlap =
          std::min(hi, origin + (i + 1) * size) - std::max(lo, origin + i * size);
      if (overlap > 0) overlaps[static_cast<std::size_t>(k)].emplace_back(i, overlap);
    }
  }
  return overlaps;
}

/// Paints `grid` with its top-left corner at (x0, y0) px and cells mw x mh px:
/// each pixel becomes the area average of paper and ink over its square.
void paint_grid(imaging::Plane& image, const ModuleGrid& grid, double x0, double y0, double mw,
                double mh, double paper, double ink) {
  const int px0 = std::max(0, static_cast<int>(std::floor(x0)));
  const int py0 = std::max(0, static_cast<int>(std::floor(y0)));
  const int px1 = std::min(image.width, whole_px(x0 + grid.cols * mw));
  const int py1 = std::min(image.height, whole_px(y0 + grid.rows * mh));
  if (px1 <= px0 || py1 <= py0) return;
  const auto wx = cell_overlaps(x0, mw, grid.cols, px0, px1 - px0);
  const auto wy = cell_overlaps(y0, mh, grid.rows, py0, py1 - py0);
  // Dark length of each module row across each pixel column, px.
  std::vector<double> row_cover(static_cast<std::size_t>(grid.rows) * (px1 - px0), 0.0);
  for (int r = 0; r < grid.rows; ++r) {
    for (int k = 0; k < px1 - px0; ++k) {
      double sum = 0;
      for (const auto& [c, w] : wx[static_cast<std::size_t>(k)]) {
        if (grid.at(c, r)) sum += w;
      }
      row_cover[static_cast<std::size_t>(r) * (px1 - px0) + k] = sum;
    }
  }
  for (int y = py0; y < py1; ++y) {
    const auto& rows = wy[static_cast<std::size_t>(y - py0)];
    if (rows.empty()) continue;
    for (int x = px0; x < px1; ++x) {
      double cover = 0;
      for (const auto& [r, h] : rows) {
        cover += h * row_cover[static_cast<std::size_t>(r) * (px1 - px0) + (x - px0)];
      }
      cover = std::clamp(cover, 0.0, 1.0);
      // Pixels the symbol only partly covers keep the paper under the rest.
      image.at(x, y) = static_cast<float>(paper + (ink - paper) * cover);
    }
  }
}

void fill_rect(imaging::Plane& image, const LabelRect& rect, float value) {
  for (int y = rect.y; y < rect.y + rect.h; ++y) {
    auto row = image.row(y);
    std::fill(row.begin() + rect.x, row.begin() + rect.x + rect.w, value);
  }
}

/// Where a barcode's symbol and label go in the image.
struct BarcodeLayout {
  ModuleGrid grid;
  bool linear = false;
  LabelRect label;
  double x0 = 0, y0 = 0;              ///< the symbol's top-left corner (pixel edges), px
  double symbol_w = 0, symbol_h = 0;  ///< px
};

Result<BarcodeLayout, std::string> barcode_layout(const SceneSpec& spec) {
  using LayoutResult = Result<BarcodeLayout, std::string>;
  auto grid_result = encode_symbol(spec.kind, spec.content);
  if (!grid_result) return LayoutResult::failure(grid_result.error());
  BarcodeLayout layout;
  layout.grid = std::move(grid_result.value());
  const double m = spec.module_px;
  layout.symbol_w = layout.grid.cols * m;
  layout.linear = spec.kind == SceneKind::kCode128 || spec.kind == SceneKind::kEan13;

  double quiet_x = 0, quiet_y = 0;  // px
  if (layout.linear) {
    quiet_x = (spec.kind == SceneKind::kEan13 ? kEan13QuietModules : kCode128QuietModules) * m;
    quiet_y = kLinearVerticalQuietModules * m;
    // As tall as wanted if the image has room, never below the least height.
    const double room = spec.height - 2.0 * kMinBeltPx - 2.0 * quiet_y;
    layout.symbol_h = std::floor(std::min(kBarHeightWanted * layout.symbol_w, room));
    layout.symbol_h = std::max(layout.symbol_h, std::ceil(kBarHeightLeast * layout.symbol_w));
  } else {
    quiet_x = quiet_y =
        (spec.kind == SceneKind::kQr ? kQrQuietModules : kDataMatrixQuietModules) * m;
    layout.symbol_h = layout.grid.rows * m;
  }
  const int label_w = whole_px(layout.symbol_w + 2 * quiet_x);
  const int label_h = whole_px(layout.symbol_h + 2 * quiet_y);
  auto rect = place_label(spec, label_w, label_h, describe(spec));
  if (!rect) return LayoutResult::failure(rect.error());
  layout.label = rect.value();
  // Centred in the label: with whole-pixel modules the symbol's edges fall on
  // pixel edges; with fractional ones the edge pixels are area averages.
  layout.x0 = layout.label.x + (layout.label.w - layout.symbol_w) / 2.0;
  layout.y0 = layout.label.y + (layout.label.h - layout.symbol_h) / 2.0;
  return LayoutResult::success(std::move(layout));
}

PlaneResult render_barcode(const SceneSpec& spec) {
  auto layout_result = barcode_layout(spec);
  if (!layout_result) return PlaneResult::failure(layout_result.error());
  const BarcodeLayout& layout = layout_result.value();
  imaging::Plane image(spec.width, spec.height, static_cast<float>(spec.belt));
  fill_rect(image, layout.label, static_cast<float>(spec.paper));
  const double cell_h = layout.linear ? layout.symbol_h : spec.module_px;
  paint_grid(image, layout.grid, layout.x0, layout.y0, spec.module_px, cell_h, spec.paper,
             spec.ink);
  return PlaneResult::success(std::move(image));
}

PlaneResult render_text(const SceneSpec& spec) {
  constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
  constexpr int kS = kTextSupersample;
  const double m = spec.module_px;
  // getTextSize's height at scale 1 is the font's cap height in pixels
  // (measured at a large scale to keep its rounding out).
  int unused_baseline = 0;
  constexpr double kProbeScale = 100;
  const double cap_at_scale1 =
      cv::getTextSize("H", kFont, kProbeScale, 1, &unused_baseline).height / kProbeScale;
  const double scale = kS * kTextCapModules * m / cap_at_scale1;
  const int thickness = std::max(1, static_cast<int>(std::lround(kS * kTextStrokeModules * m)));
  int baseline = 0;
  const cv::Size text_size = cv::getTextSize(spec.content, kFont, scale, thickness, &baseline);
  const double margin = kTextMarginModules * m;
  const int label_w = whole_px(text_size.width / static_cast<double>(kS) + 2 * margin);
  const int label_h =
      whole_px((text_size.height + baseline) / static_cast<double>(kS) + 2 * margin);
  auto rect = place_label(spec, label_w, label_h, describe(spec));
  if (!rect) return PlaneResult::failure(rect.error());
  const LabelRect& label = rect.value();

  // Ink coverage drawn at kS times the label's resolution, then area-averaged.
  cv::Mat canvas = cv::Mat::zeros(label.h * kS, label.w * kS, CV_8UC1);
  const cv::Point origin((canvas.cols - text_size.width + thickness) / 2,
                         (canvas.rows + text_size.height - baseline) / 2);
  cv::putText(canvas, spec.content, origin, kFont, scale, cv::Scalar(255), thickness, cv::LINE_AA);
  cv::Mat fine, cover;
  canvas.convertTo(fine, CV_32F, 1.0 / 255.0);
  cv::resize(fine, cover, cv::Size(label.w, label.h), 0, 0, cv::INTER_AREA);

  imaging::Plane image(spec.width, spec.height, static_cast<float>(spec.belt));
  for (int y = 0; y < label.h; ++y) {
    const float* c = cover.ptr<float>(y);
    for (int x = 0; x < label.w; ++x) {
      const double a = std::clamp(static_cast<double>(c[x]), 0.0, 1.0);
      image.at(label.x + x, label.y + y) =
          static_cast<float>(spec.paper + (spec.ink - spec.paper) * a);
    }
  }
  return PlaneResult::success(std::move(image));
}

double srgb_to_linear(double v) {
  return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
}

PlaneResult render_image(const SceneSpec& spec) {
  const std::string& path = spec.content;
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    return PlaneResult::failure("image '" + path + "' is not a readable file");
  }
  cv::Mat raw;
  try {
    raw = cv::imread(path, cv::IMREAD_ANYDEPTH | cv::IMREAD_ANYCOLOR);
  } catch (const cv::Exception& e) {
    return PlaneResult::failure("cannot read image '" + path + "': " + e.what());
  }
  if (raw.empty()) {
    return PlaneResult::failure("cannot read image '" + path +
                                "': not an image format OpenCV can decode");
  }
  if (raw.channels() != 1 && raw.channels() != 3) {
    return PlaneResult::failure("image '" + path + "' has " + std::to_string(raw.channels()) +
                                " channels; expected grey or colour");
  }

  // Linear light, each channel in [0, 1].
  cv::Mat linear;
  switch (raw.depth()) {
    case CV_8U: {
      cv::Mat lut(1, 256, CV_32F);
      for (int i = 0; i < 256; ++i)
        lut.at<float>(i) = static_cast<float>(srgb_to_linear(i / 255.0));
      cv::LUT(raw, lut, linear);
      break;
    }
    case CV_16U: {
      std::vector<float> table(65536);
      for (std::size_t i = 0; i < table.size(); ++i) {
        table[i] = static_cast<float>(srgb_to_linear(static_cast<double>(i) / 65535.0));
      }
      linear.create(raw.size(), CV_MAKETYPE(CV_32F, raw.channels()));
      for (int y = 0; y < raw.rows; ++y) {
        const auto* in = raw.ptr<std::uint16_t>(y);
        auto* out = linear.ptr<float>(y);
        const int n = raw.cols * raw.channels();
        for (int i = 0; i < n; ++i) out[i] = table[in[i]];
      }
      break;
    }
    case CV_32F:
      linear = raw;
      break;
    default:
      return PlaneResult::failure("image '" + path +
                                  "' has a sample type other than 8-bit, 16-bit or float");
  }

  cv::Mat grey;
  if (linear.channels() == 3) {
    // OpenCV stores B, G, R: Rec. 709 luminance weights in that order.
    cv::transform(linear, grey, cv::Matx13f(0.0722f, 0.7152f, 0.2126f));
  } else {
    grey = linear;
  }
  cv::patchNaNs(grey, 0.0);
  grey = cv::min(cv::max(grey, 0.0), 1.0);

  // Shrink with area averaging, enlarge (any axis still short) bilinearly.
  const cv::Size target(spec.width, spec.height);
  cv::Mat sized = grey;
  const cv::Size shrunk(std::min(target.width, grey.cols), std::min(target.height, grey.rows));
  if (shrunk != grey.size()) cv::resize(grey, sized, shrunk, 0, 0, cv::INTER_AREA);
  if (sized.size() != target) {
    cv::Mat enlarged;
    cv::resize(sized, enlarged, target, 0, 0, cv::INTER_LINEAR);
    sized = enlarged;
  }

  imaging::Plane image(spec.width, spec.height);
  for (int y = 0; y < spec.height; ++y) {
    const float* in = sized.ptr<float>(y);
    auto row = image.row(y);
    for (int x = 0; x < spec.width; ++x)
      row[static_cast<std::size_t>(x)] = std::clamp(in[x], 0.0f, 1.0f);
  }
  return PlaneResult::success(std::move(image));
}

}  // namespace

std::string_view scene_kind_name(SceneKind kind) {
  for (const KindName& k : kKindNames) {
    if (k.kind == kind) return k.name;
  }
  return "unknown";
}

Result<SceneSpec, std::string> parse_scene(const std::string& text) {
  using SpecResult = Result<SceneSpec, std::string>;
  const std::size_t colon = text.find(':');
  if (colon == std::string::npos) {
    return SpecResult::failure("scene '" + text +
                               "' names no kind: write KIND:CONTENT, e.g. code128:HELLO; the "
                               "kinds are " +
                               kind_list());
  }
  const std::string kind_text = text.substr(0, colon);
  const std::string lower = to_lower(kind_text);
  const auto found = std::find_if(kKindNames.begin(), kKindNames.end(),
                                  [&](const KindName& k) { return k.name == lower; });
  if (found == kKindNames.end()) {
    return SpecResult::failure("unknown scene kind '" + kind_text + "'; the kinds are " +
                               kind_list());
  }
  SceneSpec spec;
  spec.kind = found->kind;
  spec.content = text.substr(colon + 1);
  const std::string problem = content_problem(spec.kind, spec.content);
  if (!problem.empty()) return SpecResult::failure(problem);
  return SpecResult::success(std::move(spec));
}

PlaneResult render_scene(const SceneSpec& camera_spec, int supersample) {
  if (std::string problem = spec_problem(camera_spec); !problem.empty()) {
    return PlaneResult::failure(problem);
  }
  if (supersample < 1 || supersample > 16)
    return PlaneResult::failure("supersampling must be 1 to 16");
  SceneSpec spec = camera_spec;  // on the fine grid
  spec.width *= supersample;
  spec.height *= supersample;
  spec.module_px *= supersample;
  // The checks parse_scene() makes, for specs built in code. (Hershey fonts
  // have glyphs for printable ASCII only.)
  if (std::string problem = content_problem(spec.kind, spec.content); !problem.empty()) {
    return PlaneResult::failure(problem);
  }
  if (spec.kind == SceneKind::kImage) return render_image(spec);
  if (spec.kind == SceneKind::kPhoto) {
    auto bands = render_photo_bands(camera_spec, supersample);
    if (!bands.ok()) return PlaneResult::failure(bands.error());
    return PlaneResult::success(fuse_bands(bands.value()));
  }
  if (spec.kind == SceneKind::kFlat)
    return PlaneResult::success(imaging::Plane(spec.width, spec.height, std::stof(spec.content)));
  PlaneResult label = spec.kind == SceneKind::kText ? render_text(spec) : render_barcode(spec);
  if (!label.ok()) return label;
  return PlaneResult::success(weather_print(std::move(label.value()), camera_spec, supersample));
}

Result<SymbolPlacement, std::string> symbol_placement(const SceneSpec& spec) {
  using PlacementResult = Result<SymbolPlacement, std::string>;
  if (std::string problem = spec_problem(spec); !problem.empty())
    return PlacementResult::failure(problem);
  if (std::string problem = content_problem(spec.kind, spec.content); !problem.empty())
    return PlacementResult::failure(problem);
  const char* id = spec.kind == SceneKind::kCode128      ? "]C0"
                   : spec.kind == SceneKind::kEan13      ? "]E0"
                   : spec.kind == SceneKind::kQr         ? "]Q1"
                   : spec.kind == SceneKind::kDataMatrix ? "]d1"
                                                         : nullptr;
  if (id == nullptr)
    return PlacementResult::failure(std::string(scene_kind_name(spec.kind)) +
                                    " scenes hold no barcode");
  auto layout = barcode_layout(spec);
  if (!layout) return PlacementResult::failure(layout.error());
  SymbolPlacement p;
  // Pixel edges to pixel centres: pixel x covers [x, x + 1) and its centre is x.
  const double left = layout.value().x0 - 0.5, top = layout.value().y0 - 0.5;
  const double right = left + layout.value().symbol_w, bottom = top + layout.value().symbol_h;
  p.corners = {{{left, top}, {right, top}, {right, bottom}, {left, bottom}}};
  p.module_px = spec.module_px;
  p.modules = layout.value().grid.cols;
  p.symbology_id = id;
  return PlacementResult::success(std::move(p));
}

int ean13_check_digit(std::string_view digits) {
  int sum = 0;
  for (std::size_t i = 0; i < 12; ++i) sum += (digits[i] - '0') * (i % 2 == 0 ? 1 : 3);
  return (10 - sum % 10) % 10;
}

}  // namespace flutterscan::sim
