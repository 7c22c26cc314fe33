#pragma once
// The V4L2 pixel formats the v4l2 backend accepts, and what each does to the
// linear per-channel model: raw Bayer, RGB24/BGR24 and grey keep the colour
// channels apart; YUYV and MJPEG mix them (accepted with a warning).
// Pure table lookups: no device access.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace flutterscan::capture {

/// \brief How a pixel format stores the camera's colour channels.
enum class V4l2Layout {
  kBayer,  ///< One colour sample per pixel in a 2x2 mosaic (raw, unprocessed).
  kRgb,    ///< Three interleaved 8-bit samples per pixel, R first.
  kBgr,    ///< Three interleaved 8-bit samples per pixel, B first.
  kGrey,   ///< One luminance sample per pixel (monochrome sensor).
  kYuyv,   ///< Packed YUV 4:2:2: channels mixed, chroma shared by pixel pairs.
  kMjpeg,  ///< Motion JPEG: lossy, chroma subsampled.
};

/// \brief One accepted V4L2 pixel format.
struct V4l2FormatInfo {
  std::uint32_t fourcc = 0;
  std::string_view name;  ///< V4L2's name, e.g. "RGB3" shown as "RGB24".
  V4l2Layout layout = V4l2Layout::kRgb;
  int bits_per_sample = 8;       ///< Significant bits of one sample (10 for SRGGB10).
  int bytes_per_sample = 1;      ///< Container size (2 for 10/12/16-bit, little-endian).
  std::string_view bayer_order;  ///< "RGGB", "BGGR", "GRBG", "GBRG" for kBayer, else empty.
  /// Empty when the format keeps the channels apart; otherwise the accuracy
  /// that is lost, for the warning printed when it is chosen.
  std::string_view accuracy_loss;
};

/// \brief The entry for `fourcc`, or nothing when the backend does not accept it.
std::optional<V4l2FormatInfo> v4l2_format_info(std::uint32_t fourcc);

/// \brief Every accepted format, in the order the backend prefers them when the
/// caller asks for none: raw Bayer (deepest first), RGB24, BGR24, grey, YUYV, MJPEG.
const std::vector<V4l2FormatInfo>& v4l2_accepted_formats();

/// \brief The four characters of a fourcc code, e.g. "RGB3"; non-printable bytes as '?'.
std::string fourcc_text(std::uint32_t fourcc);

/// \brief The fourcc called `name`: a format table name ("RGB24", "SRGGB10")
/// or four characters ("RG10"); nothing when unknown.
std::optional<std::uint32_t> fourcc_from_name(std::string_view name);

}  // namespace flutterscan::capture
