#include "capture/frame_pixels.hpp"

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cstring>

namespace flutterscan::capture {
namespace {

using Out = Result<imaging::Image, std::string>;

imaging::Image planes(int count, int width, int height) {
  imaging::Image image;
  for (int c = 0; c < count; ++c) image.channels.emplace_back(width, height);
  return image;
}

std::uint16_t read16(const std::uint8_t* p) {
  return static_cast<std::uint16_t>(p[0] | (p[1] << 8));
}

float clamp8(float v) {
  return std::clamp(v, 0.0f, 255.0f);
}

}  // namespace

Result<imaging::Image, std::string> frame_to_dn(const Frame& frame) {
  const FrameFormat& f = frame.format;
  const std::string where = "frame " + std::to_string(frame.sequence);
  if (f.width <= 0 || f.height <= 0) return Out::failure(where + ": empty size");
  if (f.pixel_format == PixelFormat::kMjpeg) {
    cv::Mat bytes(1, static_cast<int>(frame.data.size()), CV_8U,
                  const_cast<std::uint8_t*>(frame.data.data()));
    cv::Mat bgr = cv::imdecode(bytes, cv::IMREAD_COLOR);
    if (bgr.empty() || bgr.cols != f.width || bgr.rows != f.height)
      return Out::failure(where + ": MJPEG data does not decode to " + std::to_string(f.width) +
                          "x" + std::to_string(f.height));
    imaging::Image image = planes(3, f.width, f.height);
    for (int y = 0; y < f.height; ++y)
      for (int x = 0; x < f.width; ++x) {
        const auto& px = bgr.at<cv::Vec3b>(y, x);
        for (int c = 0; c < 3; ++c) image.channels[c].at(x, y) = px[2 - c];
      }
    return Out::success(std::move(image));
  }
  const int bpp = bytes_per_pixel(f.pixel_format);
  const std::size_t row_bytes =
      f.row_bytes != 0 ? f.row_bytes : static_cast<std::size_t>(f.width) * bpp;
  if (row_bytes < static_cast<std::size_t>(f.width) * bpp)
    return Out::failure(where + ": row stride " + std::to_string(row_bytes) +
                        " shorter than a row of " + std::to_string(f.width) + " pixels");
  if (frame.data.size() <
      row_bytes * static_cast<std::size_t>(f.height - 1) + static_cast<std::size_t>(f.width) * bpp)
    return Out::failure(where + ": " + std::to_string(frame.data.size()) + " bytes, " +
                        std::to_string(f.width) + "x" + std::to_string(f.height) + " " +
                        pixel_format_name(f.pixel_format) + " needs more");
  const bool colour = f.pixel_format == PixelFormat::kRgb8 ||
                      f.pixel_format == PixelFormat::kBgr8 ||
                      f.pixel_format == PixelFormat::kRgb16 || f.pixel_format == PixelFormat::kYuyv;
  imaging::Image image = planes(colour ? 3 : 1, f.width, f.height);
  for (int y = 0; y < f.height; ++y) {
    const std::uint8_t* row = frame.data.data() + row_bytes * static_cast<std::size_t>(y);
    switch (f.pixel_format) {
      case PixelFormat::kMono8:
      case PixelFormat::kBayerRggb8:
        for (int x = 0; x < f.width; ++x) image.channels[0].at(x, y) = row[x];
        break;
      case PixelFormat::kMono16:
      case PixelFormat::kBayerRggb16:
        for (int x = 0; x < f.width; ++x) image.channels[0].at(x, y) = read16(row + 2 * x);
        break;
      case PixelFormat::kRgb8:
      case PixelFormat::kBgr8: {
        const bool bgr = f.pixel_format == PixelFormat::kBgr8;
        float* r = image.channels[0].row(y).data();
        float* g = image.channels[1].row(y).data();
        float* b = image.channels[2].row(y).data();
        for (int x = 0; x < f.width; ++x) {
          r[x] = row[3 * x + (bgr ? 2 : 0)];
          g[x] = row[3 * x + 1];
          b[x] = row[3 * x + (bgr ? 0 : 2)];
        }
        break;
      }
      case PixelFormat::kRgb16:
        for (int x = 0; x < f.width; ++x)
          for (int c = 0; c < 3; ++c) image.channels[c].at(x, y) = read16(row + 6 * x + 2 * c);
        break;
      case PixelFormat::kYuyv:
        for (int x = 0; x < f.width; ++x) {
          const int pair = x & ~1;
          const float luma = row[2 * x];
          const float u = static_cast<float>(row[2 * pair + 1]) - 128.0f;
          const float v = static_cast<float>(row[2 * pair + 3]) - 128.0f;
          image.channels[0].at(x, y) = clamp8(luma + 1.402f * v);
          image.channels[1].at(x, y) = clamp8(luma - 0.344136f * u - 0.714136f * v);
          image.channels[2].at(x, y) = clamp8(luma + 1.772f * u);
        }
        break;
      case PixelFormat::kMjpeg:
        break;
    }
  }
  return Out::success(std::move(image));
}

}  // namespace flutterscan::capture
