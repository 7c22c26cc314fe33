#include "sim/photo_scene.hpp"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <numbers>
#include <sstream>
#include <system_error>
#include <utility>

#include "imaging/frame_conversion.hpp"
#include "imaging/limits.hpp"

namespace flutterscan::sim {
namespace {

/// `value` as printf's %g writes it (3, 2.5, -33).
std::string number(double value) {
  std::ostringstream text;
  text << value;
  return text.str();
}

/// The largest turn accepted either way, degrees.
constexpr double kMaxTurnDeg = 360;

/// A photo in linear light, OpenCV's B, G, R order, samples in [0, 1].
struct LinearPhoto {
  cv::Mat bgr;  ///< CV_32FC3
  bool grey = false;
};

Result<LinearPhoto, std::string> read_photo(const std::string& path) {
  using Out = Result<LinearPhoto, std::string>;
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    return Out::failure("photo '" + path + "' is not a readable file");
  cv::Mat raw;
  try {
    raw = cv::imread(path, cv::IMREAD_ANYDEPTH | cv::IMREAD_COLOR);
  } catch (const cv::Exception& e) {
    return Out::failure("cannot read photo '" + path + "': " + e.what());
  }
  if (raw.empty())
    return Out::failure("cannot read photo '" + path + "': not an image format OpenCV can decode");
  if (raw.cols > imaging::kMaxFrameSidePx || raw.rows > imaging::kMaxFrameSidePx)
    return Out::failure("photo '" + path + "' is " + std::to_string(raw.cols) + " x " +
                        std::to_string(raw.rows) + " px; the largest side taken is " +
                        std::to_string(imaging::kMaxFrameSidePx));
  LinearPhoto photo;
  switch (raw.depth()) {
    case CV_8U:
    case CV_16U: {
      const int levels = raw.depth() == CV_8U ? 256 : 65536;
      std::vector<float> table(static_cast<std::size_t>(levels));
      for (int i = 0; i < levels; ++i)
        table[static_cast<std::size_t>(i)] =
            static_cast<float>(imaging::srgb_to_linear(static_cast<double>(i) / (levels - 1)));
      photo.bgr.create(raw.size(), CV_32FC3);
      for (int y = 0; y < raw.rows; ++y) {
        auto* out = photo.bgr.ptr<float>(y);
        const int n = raw.cols * 3;
        if (raw.depth() == CV_8U) {
          const auto* in = raw.ptr<std::uint8_t>(y);
          for (int i = 0; i < n; ++i) out[i] = table[in[i]];
        } else {
          const auto* in = raw.ptr<std::uint16_t>(y);
          for (int i = 0; i < n; ++i) out[i] = table[in[i]];
        }
      }
      break;
    }
    case CV_32F:
      photo.bgr = raw;
      cv::patchNaNs(photo.bgr, 0.0);
      photo.bgr = cv::min(cv::max(photo.bgr, 0.0), 1.0);
      break;
    default:
      return Out::failure("photo '" + path +
                          "' has a sample type other than 8-bit, 16-bit or float");
  }
  photo.grey = true;
  for (int y = 0; y < photo.bgr.rows && photo.grey; ++y) {
    const auto* p = photo.bgr.ptr<cv::Vec3f>(y);
    for (int x = 0; x < photo.bgr.cols; ++x)
      if (p[x][0] != p[x][1] || p[x][1] != p[x][2]) {
        photo.grey = false;
        break;
      }
  }
  return Out::success(std::move(photo));
}

std::string spec_problem(const SceneSpec& spec) {
  if (spec.kind != SceneKind::kPhoto) return "not a photo scene";
  if (!std::isfinite(spec.rotate_deg) || std::abs(spec.rotate_deg) > kMaxTurnDeg)
    return "photo turn " + number(spec.rotate_deg) + " degrees is not a number from -" +
           number(kMaxTurnDeg) + " to " + number(kMaxTurnDeg);
  if (!(spec.belt >= 0 && spec.belt <= 1)) return "belt reflectance is outside 0..1";
  return {};
}

/// The turned photo's bounding box, camera pixels, rounded up (a hair of
/// floating-point error is not a pixel).
std::pair<int, int> turned_box(int width, int height, double rotate_deg) {
  const double a = rotate_deg * std::numbers::pi / 180;
  const double c = std::abs(std::cos(a)), s = std::abs(std::sin(a));
  return {static_cast<int>(std::ceil(width * c + height * s - 1e-6)),
          static_cast<int>(std::ceil(width * s + height * c - 1e-6))};
}

Result<PhotoLayout, std::string> layout_of(const SceneSpec& spec, const LinearPhoto& photo) {
  using Out = Result<PhotoLayout, std::string>;
  PhotoLayout l;
  l.photo_width = photo.bgr.cols;
  l.photo_height = photo.bgr.rows;
  l.grey = photo.grey;
  std::tie(l.box_width, l.box_height) = turned_box(l.photo_width, l.photo_height, spec.rotate_deg);
  const int need_w = l.box_width + 2 * kMinBeltPx, need_h = l.box_height + 2 * kMinBeltPx;
  if (spec.width < need_w || spec.height < need_h)
    return Out::failure("photo '" + spec.content + "' (" + std::to_string(l.photo_width) + " x " +
                        std::to_string(l.photo_height) + " px, turned " + number(spec.rotate_deg) +
                        " degrees) needs a frame of at least " + std::to_string(need_w) + " x " +
                        std::to_string(need_h) + " px, not " + std::to_string(spec.width) + " x " +
                        std::to_string(spec.height));
  // Whole-pixel offsets: unturned, the photo's pixels are the camera's.
  l.centre_x = (spec.width - l.photo_width) / 2 + l.photo_width / 2.0;
  l.centre_y = (spec.height - l.photo_height) / 2 + l.photo_height / 2.0;
  return Out::success(l);
}

}  // namespace

Result<PhotoLayout, std::string> photo_layout(const SceneSpec& spec) {
  using Out = Result<PhotoLayout, std::string>;
  if (auto problem = spec_problem(spec); !problem.empty()) return Out::failure(problem);
  auto photo = read_photo(spec.content);
  if (!photo.ok()) return Out::failure(photo.error());
  return layout_of(spec, photo.value());
}

Result<std::pair<int, int>, std::string> photo_frame_size(const SceneSpec& spec) {
  using Out = Result<std::pair<int, int>, std::string>;
  if (auto problem = spec_problem(spec); !problem.empty()) return Out::failure(problem);
  auto photo = read_photo(spec.content);
  if (!photo.ok()) return Out::failure(photo.error());
  const auto [w, h] = turned_box(photo.value().bgr.cols, photo.value().bgr.rows, spec.rotate_deg);
  return Out::success(std::pair{w + 2 * kMinBeltPx, h + 2 * kMinBeltPx});
}

Result<std::vector<imaging::Plane>, std::string> render_photo_bands(const SceneSpec& spec,
                                                                    int supersample) {
  using Out = Result<std::vector<imaging::Plane>, std::string>;
  if (auto problem = spec_problem(spec); !problem.empty()) return Out::failure(problem);
  if (supersample < 1 || supersample > 16) return Out::failure("supersampling must be 1 to 16");
  auto photo = read_photo(spec.content);
  if (!photo.ok()) return Out::failure(photo.error());
  auto layout = layout_of(spec, photo.value());
  if (!layout.ok()) return Out::failure(layout.error());
  const PhotoLayout& l = layout.value();

  cv::Mat reflectance;
  photo.value().bgr.convertTo(reflectance, CV_32FC3, kPhotoWhite - kPhotoBlack, kPhotoBlack);
  // Fine pixel (i, j) -> photo pixel index: its centre, in camera pixels, turned
  // back about the photo's centre (anticlockwise on the image, y down, by
  // rotate_deg), nearest photo pixel: each photo pixel is a square of one reflectance.
  const double k = supersample;
  const double a = spec.rotate_deg * std::numbers::pi / 180;
  const double c = std::cos(a), s = std::sin(a);
  const double dx = 0.5 / k - l.centre_x, dy = 0.5 / k - l.centre_y;
  const cv::Matx23d to_photo(c / k, -s / k, c * dx - s * dy + l.photo_width / 2.0 - 0.5,  //
                             s / k, c / k, s * dx + c * dy + l.photo_height / 2.0 - 0.5);
  const cv::Size fine(spec.width * supersample, spec.height * supersample);
  cv::Mat placed;
  cv::warpAffine(reflectance, placed, to_photo, fine, cv::INTER_NEAREST | cv::WARP_INVERSE_MAP,
                 cv::BORDER_CONSTANT, cv::Scalar::all(spec.belt));

  std::vector<imaging::Plane> bands;
  for (const int channel : {2, 1, 0}) {  // OpenCV's B, G, R -> the red, green, blue LEDs
    imaging::Plane band = imaging::Plane::uninitialised(fine.width, fine.height);
    for (int y = 0; y < fine.height; ++y) {
      const auto* in = placed.ptr<cv::Vec3f>(y);
      auto row = band.row(y);
      for (int x = 0; x < fine.width; ++x) row[static_cast<std::size_t>(x)] = in[x][channel];
    }
    bands.push_back(std::move(band));
  }
  return Out::success(std::move(bands));
}

}  // namespace flutterscan::sim
