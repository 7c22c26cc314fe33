#include "capture/v4l2_formats.hpp"

#include <linux/videodev2.h>

#include <algorithm>

namespace flutterscan::capture {
namespace {

constexpr std::string_view kYuyvLoss =
    "YUYV mixes R, G and B into luma and two chroma signals shared by each pixel pair: the three "
    "LED codes are no longer separate channels and colour detail is halved horizontally, so "
    "per-channel deblurring is approximate";
constexpr std::string_view kMjpegLoss =
    "MJPEG is lossy: chroma subsampling mixes the channels and JPEG quantisation adds block "
    "artefacts and non-Gaussian noise, so per-channel deblurring is approximate";

std::vector<V4l2FormatInfo> build_table() {
  std::vector<V4l2FormatInfo> table;
  struct Bayer {
    std::string_view order;
    std::uint32_t f8, f10, f12, f16;
    std::string_view n8, n10, n12, n16;
  };
  const Bayer bayers[] = {
      {"RGGB", V4L2_PIX_FMT_SRGGB8, V4L2_PIX_FMT_SRGGB10, V4L2_PIX_FMT_SRGGB12,
       V4L2_PIX_FMT_SRGGB16, "SRGGB8", "SRGGB10", "SRGGB12", "SRGGB16"},
      {"BGGR", V4L2_PIX_FMT_SBGGR8, V4L2_PIX_FMT_SBGGR10, V4L2_PIX_FMT_SBGGR12,
       V4L2_PIX_FMT_SBGGR16, "SBGGR8", "SBGGR10", "SBGGR12", "SBGGR16"},
      {"GRBG", V4L2_PIX_FMT_SGRBG8, V4L2_PIX_FMT_SGRBG10, V4L2_PIX_FMT_SGRBG12,
       V4L2_PIX_FMT_SGRBG16, "SGRBG8", "SGRBG10", "SGRBG12", "SGRBG16"},
      {"GBRG", V4L2_PIX_FMT_SGBRG8, V4L2_PIX_FMT_SGBRG10, V4L2_PIX_FMT_SGBRG12,
       V4L2_PIX_FMT_SGBRG16, "SGBRG8", "SGBRG10", "SGBRG12", "SGBRG16"},
  };
  // Deepest Bayer first: most bits of the linear signal.
  for (const Bayer& b : bayers)
    table.push_back({b.f16, b.n16, V4l2Layout::kBayer, 16, 2, b.order, {}});
  for (const Bayer& b : bayers)
    table.push_back({b.f12, b.n12, V4l2Layout::kBayer, 12, 2, b.order, {}});
  for (const Bayer& b : bayers)
    table.push_back({b.f10, b.n10, V4l2Layout::kBayer, 10, 2, b.order, {}});
  for (const Bayer& b : bayers)
    table.push_back({b.f8, b.n8, V4l2Layout::kBayer, 8, 1, b.order, {}});
  table.push_back({V4L2_PIX_FMT_RGB24, "RGB24", V4l2Layout::kRgb, 8, 1, {}, {}});
  table.push_back({V4L2_PIX_FMT_BGR24, "BGR24", V4l2Layout::kBgr, 8, 1, {}, {}});
  table.push_back({V4L2_PIX_FMT_Y16, "Y16", V4l2Layout::kGrey, 16, 2, {}, {}});
  table.push_back({V4L2_PIX_FMT_GREY, "GREY", V4l2Layout::kGrey, 8, 1, {}, {}});
  table.push_back({V4L2_PIX_FMT_YUYV, "YUYV", V4l2Layout::kYuyv, 8, 1, {}, kYuyvLoss});
  table.push_back({V4L2_PIX_FMT_MJPEG, "MJPEG", V4l2Layout::kMjpeg, 8, 1, {}, kMjpegLoss});
  return table;
}

}  // namespace

const std::vector<V4l2FormatInfo>& v4l2_accepted_formats() {
  static const std::vector<V4l2FormatInfo> table = build_table();
  return table;
}

std::optional<V4l2FormatInfo> v4l2_format_info(std::uint32_t fourcc) {
  for (const V4l2FormatInfo& info : v4l2_accepted_formats()) {
    if (info.fourcc == fourcc) return info;
  }
  return std::nullopt;
}

std::string fourcc_text(std::uint32_t fourcc) {
  std::string text(4, '?');
  for (int i = 0; i < 4; ++i) {
    const char c = static_cast<char>((fourcc >> (8 * i)) & 0xff);
    if (c >= 0x20 && c < 0x7f) text[i] = c;
  }
  return text;
}

std::optional<std::uint32_t> fourcc_from_name(std::string_view name) {
  for (const V4l2FormatInfo& info : v4l2_accepted_formats()) {
    if (info.name == name) return info.fourcc;
  }
  if (name.size() == 4) {
    return v4l2_fourcc(name[0], name[1], name[2], name[3]);
  }
  return std::nullopt;
}

}  // namespace flutterscan::capture
