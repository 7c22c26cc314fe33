#include "capture/frame_pixels.hpp"

#include <opencv2/imgcodecs.hpp>

#include "imaging/frame_conversion.hpp"
#include "imaging/limits.hpp"
#include "imaging/model_guards.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <span>
#include <utility>
#include <vector>

namespace flutterscan::capture {
namespace {

static_assert(std::endian::native == std::endian::little,
              "16-bit frames are copied as they are: a big-endian host would need a byte swap");

using Out = Result<imaging::Image, std::string>;

/// `count` planes whose every sample the caller writes.
imaging::Image planes(int count, int width, int height) {
  imaging::Image image;
  for (int c = 0; c < count; ++c)
    image.channels.push_back(imaging::Plane::uninitialised(width, height));
  return image;
}

std::uint16_t read16(const std::uint8_t* p) {
  return static_cast<std::uint16_t>(p[0] | (p[1] << 8));
}

std::size_t row_stride(const FrameFormat& f) {
  return f.row_bytes != 0 ? f.row_bytes
                          : static_cast<std::size_t>(f.width) * bytes_per_pixel(f.pixel_format);
}

/// "" if the frame's data holds its format's rows (uncompressed formats), else what does not fit.
std::string layout_problem(const Frame& frame) {
  const FrameFormat& f = frame.format;
  const std::string where = "frame " + std::to_string(frame.sequence);
  const std::size_t row_bytes = row_stride(f);
  const auto pixels_bytes = static_cast<std::size_t>(f.width) * bytes_per_pixel(f.pixel_format);
  // YUYV packs two pixels in 4 bytes (Y0 U Y1 V): a width that is odd has no V for its last pixel.
  if (f.pixel_format == PixelFormat::kYuyv && f.width % 2 != 0)
    return where + ": yuyv needs an even width, not " + std::to_string(f.width);
  if (row_bytes < pixels_bytes)
    return where + ": row stride " + std::to_string(row_bytes) + " shorter than a row of " +
           std::to_string(f.width) + " pixels";
  if (frame.data.size() < row_bytes * static_cast<std::size_t>(f.height - 1) + pixels_bytes)
    return where + ": " + std::to_string(frame.data.size()) + " bytes, " + std::to_string(f.width) +
           "x" + std::to_string(f.height) + " " + pixel_format_name(f.pixel_format) + " needs more";
  return {};
}

/// Sample i of a row of `Sample`s at any alignment, little-endian as the
/// formats store them (a frame's bytes are not an array of 16-bit values).
template <typename Sample>
float sample_at(const std::uint8_t* row, std::size_t i) {
  if constexpr (sizeof(Sample) == 1)
    return row[i];
  else
    return read16(row + 2 * i);
}

/// Three interleaved samples per pixel into three float rows (vectorised).
template <typename Sample>
void deinterleave3(const std::uint8_t* __restrict row, int width, float* __restrict a,
                   float* __restrict b, float* __restrict c) {
  for (std::size_t x = 0; x < static_cast<std::size_t>(width); ++x) {
    a[x] = sample_at<Sample>(row, 3 * x);
    b[x] = sample_at<Sample>(row, 3 * x + 1);
    c[x] = sample_at<Sample>(row, 3 * x + 2);
  }
}

/// One row of interleaved samples (three per pixel, in the order of `out`) into
/// electrons in one pass, counting samples at or above `ceiling` DN.
template <typename Sample>
std::size_t row3_to_electrons(const std::uint8_t* __restrict row, int width, float black,
                              float gain, float ceiling, float* __restrict a, float* __restrict b,
                              float* __restrict c) {
  std::size_t saturated = 0;
  for (std::size_t x = 0; x < static_cast<std::size_t>(width); ++x) {
    const float da = sample_at<Sample>(row, 3 * x), db = sample_at<Sample>(row, 3 * x + 1),
                dc = sample_at<Sample>(row, 3 * x + 2);
    saturated += (da >= ceiling ? 1 : 0) + (db >= ceiling ? 1 : 0) + (dc >= ceiling ? 1 : 0);
    a[x] = (da - black) * gain;
    b[x] = (db - black) * gain;
    c[x] = (dc - black) * gain;
  }
  return saturated;
}

/// One row of samples (one per pixel) into electrons, counting samples at or
/// above `ceiling` DN.
template <typename Sample>
std::size_t row_to_electrons(const std::uint8_t* __restrict row, int width, float black, float gain,
                             float ceiling, float* __restrict out) {
  std::size_t saturated = 0;
  for (std::size_t x = 0; x < static_cast<std::size_t>(width); ++x) {
    const float dn = sample_at<Sample>(row, x);
    saturated += dn >= ceiling ? 1 : 0;
    out[x] = (dn - black) * gain;
  }
  return saturated;
}

/// The frame size a JPEG's header declares (its SOFn segment), or what is wrong with the
/// header: read before decoding, so that a buffer declaring 30000 x 30000 px is refused
/// for the frame's format instead of sizing the decoder's allocation (gigabytes).
Result<std::pair<int, int>, std::string> jpeg_declared_size(std::span<const std::uint8_t> data) {
  using Size = Result<std::pair<int, int>, std::string>;
  if (data.size() < 4 || data[0] != 0xFF || data[1] != 0xD8)
    return Size::failure("not JPEG data (no start-of-image marker)");
  std::size_t at = 2;
  while (at + 4 <= data.size()) {
    if (data[at] != 0xFF)
      return Size::failure("a JPEG marker is broken at byte " + std::to_string(at));
    const std::uint8_t marker = data[at + 1];
    if (marker == 0xFF) {  // fill byte
      ++at;
      continue;
    }
    if (marker == 0x01 || (marker >= 0xD0 && marker <= 0xD7)) {  // no length
      at += 2;
      continue;
    }
    if (marker == 0xD9 || marker == 0xDA) break;  // end of image or scan data: no frame header
    const std::size_t length = static_cast<std::size_t>(data[at + 2]) << 8 | data[at + 3];
    if (length < 2 || at + 2 + length > data.size())
      return Size::failure("a JPEG segment at byte " + std::to_string(at) + " runs past the data");
    const bool frame_header =
        marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC;
    if (frame_header) {
      if (length < 7) return Size::failure("the JPEG frame header is short");
      const int height = data[at + 5] << 8 | data[at + 6];
      const int width = data[at + 7] << 8 | data[at + 8];
      return Size::success({width, height});
    }
    at += 2 + length;
  }
  return Size::failure("the JPEG data has no frame header");
}

float clamp8(float v) {
  return std::clamp(v, 0.0f, 255.0f);
}

}  // namespace

Result<imaging::Image, std::string> frame_to_dn(const Frame& frame) {
  const FrameFormat& f = frame.format;
  const std::string where = "frame " + std::to_string(frame.sequence);
  if (f.width <= 0 || f.height <= 0) return Out::failure(where + ": empty size");
  if (f.width > imaging::kMaxFrameSidePx || f.height > imaging::kMaxFrameSidePx ||
      static_cast<long long>(f.width) * f.height > imaging::kMaxFramePixels)
    return Out::failure(where + ": " + std::to_string(f.width) + "x" + std::to_string(f.height) +
                        " px is beyond the largest frame (" +
                        std::to_string(imaging::kMaxFrameSidePx) + " px a side, " +
                        std::to_string(imaging::kMaxFramePixels) + " px)");
  if (f.pixel_format == PixelFormat::kMjpeg) {
    // An empty or broken buffer (a camera can deliver one) is an error, never an exception.
    if (frame.data.empty() ||
        frame.data.size() > static_cast<std::size_t>(std::numeric_limits<int>::max()))
      return Out::failure(where + ": MJPEG frame of " + std::to_string(frame.data.size()) +
                          " bytes");
    const auto declared = jpeg_declared_size(frame.data);
    if (!declared.ok()) return Out::failure(where + ": MJPEG frame: " + declared.error());
    const auto [jpeg_width, jpeg_height] = declared.value();
    if (jpeg_width != f.width || jpeg_height != f.height)
      return Out::failure(where + ": MJPEG data declares " + std::to_string(jpeg_width) + "x" +
                          std::to_string(jpeg_height) + " px, the frame format " +
                          std::to_string(f.width) + "x" + std::to_string(f.height));
    cv::Mat bytes(1, static_cast<int>(frame.data.size()), CV_8U,
                  const_cast<std::uint8_t*>(frame.data.data()));
    cv::Mat bgr;
    try {
      bgr = cv::imdecode(bytes, cv::IMREAD_COLOR);
    } catch (const cv::Exception& e) {
      return Out::failure(where + ": MJPEG data does not decode: " + e.what());
    }
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
  const std::size_t row_bytes = row_stride(f);
  if (auto problem = layout_problem(frame); !problem.empty()) return Out::failure(problem);
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
        deinterleave3<std::uint8_t>(row, f.width, image.channels[bgr ? 2 : 0].row(y).data(),
                                    image.channels[1].row(y).data(),
                                    image.channels[bgr ? 0 : 2].row(y).data());
        break;
      }
      case PixelFormat::kRgb16:
        deinterleave3<std::uint16_t>(row, f.width, image.channels[0].row(y).data(),
                                     image.channels[1].row(y).data(),
                                     image.channels[2].row(y).data());
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

Result<ElectronFrame, std::string> frame_to_electrons(const Frame& frame,
                                                      const imaging::CaptureModel& model) {
  using Converted = Result<ElectronFrame, std::string>;
  const FrameFormat& f = frame.format;
  const PixelFormat p = f.pixel_format;
  const bool one_pass =
      model.encoding == imaging::Encoding::kLinear &&
      (p == PixelFormat::kRgb8 || p == PixelFormat::kBgr8 || p == PixelFormat::kRgb16 ||
       p == PixelFormat::kMono8 || p == PixelFormat::kMono16 || p == PixelFormat::kBayerRggb8 ||
       p == PixelFormat::kBayerRggb16);
  if (!one_pass) {
    auto dn = frame_to_dn(frame);
    if (!dn.ok()) return Converted::failure(dn.error());
    ElectronFrame out;
    out.electrons = imaging::dn_to_electrons(dn.value(), model);
    out.saturated_share = imaging::saturated_share(dn.value(), model);
    return Converted::success(std::move(out));
  }
  if (f.width <= 0 || f.height <= 0)
    return Converted::failure("frame " + std::to_string(frame.sequence) + ": empty size");
  if (auto problem = layout_problem(frame); !problem.empty()) return Converted::failure(problem);
  const std::size_t row_bytes = row_stride(f);
  const int channels =
      p == PixelFormat::kRgb8 || p == PixelFormat::kBgr8 || p == PixelFormat::kRgb16 ? 3 : 1;
  const bool wide =
      p == PixelFormat::kRgb16 || p == PixelFormat::kMono16 || p == PixelFormat::kBayerRggb16;
  // The sample order of the planes R, G, B: BGR8 stores blue first.
  const int first = p == PixelFormat::kBgr8 ? 2 : 0;
  const auto black = static_cast<float>(model.black_level);
  const auto gain = static_cast<float>(model.gain);
  const auto ceiling = static_cast<float>(imaging::saturation_ceiling_dn(model));
  ElectronFrame out;
  out.electrons = planes(channels, f.width, f.height);
  // Row levels for a motion frame's rows: a Bayer mosaic is split into planes first.
  const bool mosaic = is_bayer_mosaic(p);
  if (!mosaic) out.levels = imaging::RowLevels(channels, f.height, f.width);
  std::size_t saturated = 0;
  for (int y = 0; y < f.height; ++y) {
    const std::uint8_t* row = frame.data.data() + row_bytes * static_cast<std::size_t>(y);
    if (channels == 3) {
      // The planes in the samples' order: R, G, B (BGR8: B, G, R).
      auto plane = [&](int c) {
        return out.electrons.channels[static_cast<std::size_t>(c)].row(y).data();
      };
      float* const a = plane(first);
      float* const b = plane(1);
      float* const c = plane(2 - first);
      saturated +=
          wide ? row3_to_electrons<std::uint16_t>(row, f.width, black, gain, ceiling, a, b, c)
               : row3_to_electrons<std::uint8_t>(row, f.width, black, gain, ceiling, a, b, c);
    } else {
      float* to = out.electrons.channels[0].row(y).data();
      saturated += wide ? row_to_electrons<std::uint16_t>(row, f.width, black, gain, ceiling, to)
                        : row_to_electrons<std::uint8_t>(row, f.width, black, gain, ceiling, to);
    }
    for (int c = 0; c < (mosaic ? 0 : channels); ++c)
      out.levels.set(
          c, y, imaging::row_level(out.electrons.channels[static_cast<std::size_t>(c)].row(y)));
  }
  out.saturated_share =
      static_cast<double>(saturated) / (static_cast<double>(channels) * f.width * f.height);
  // Every value is (sample - black) x gain with 0 <= sample <= the format's largest: finite
  // black and gain bound them (a factor of 2 to spare for float rounding).
  const double largest_sample = wide ? 65535.0 : 255.0;
  if (std::isfinite(black) && std::isfinite(gain) &&
      2 * (largest_sample + std::abs(black)) * std::abs(gain) <= imaging::kMaxPixelValue)
    out.values = imaging::PixelValues::kShownInRange;
  return Converted::success(std::move(out));
}

}  // namespace flutterscan::capture
