#include "capture/camera_source.hpp"

#include <array>
#include <utility>

#include "capture/backends.hpp"

namespace flutterscan::capture {
namespace {

struct PixelFormatEntry {
  PixelFormat format;
  const char* name;
  int bytes;
};

constexpr std::array<PixelFormatEntry, 9> kPixelFormats{{
    {PixelFormat::kMono8, "mono8", 1},
    {PixelFormat::kMono16, "mono16", 2},
    {PixelFormat::kRgb8, "rgb8", 3},
    {PixelFormat::kBgr8, "bgr8", 3},
    {PixelFormat::kRgb16, "rgb16", 6},
    {PixelFormat::kBayerRggb8, "bayer-rggb8", 1},
    {PixelFormat::kBayerRggb16, "bayer-rggb16", 2},
    {PixelFormat::kYuyv, "yuyv", 2},
    {PixelFormat::kMjpeg, "mjpeg", 0},
}};

/// The backends compiled in (backends.hpp), made on first use.
const std::vector<CameraBackend>& builtin_backends() {
  static const std::vector<CameraBackend> backends = [] {
    std::vector<CameraBackend> all;
#ifdef FLUTTERSCAN_HAVE_V4L2
    all.push_back(v4l2_camera_backend());
#endif
#ifdef FLUTTERSCAN_HAVE_ARAVIS
    all.push_back(aravis_camera_backend());
#endif
#ifdef FLUTTERSCAN_HAVE_LIBCAMERA
    all.push_back(libcamera_camera_backend());
#endif
    all.push_back(files_camera_backend());
    all.push_back(sim_camera_backend());
    return all;
  }();
  return backends;
}

}  // namespace

std::string pixel_format_name(PixelFormat format) {
  for (const auto& entry : kPixelFormats) {
    if (entry.format == format) return entry.name;
  }
  return "unknown";
}

std::optional<PixelFormat> pixel_format_from_name(const std::string& name) {
  for (const auto& entry : kPixelFormats) {
    if (name == entry.name) return entry.format;
  }
  return std::nullopt;
}

bool keeps_channels_apart(PixelFormat format) {
  return format != PixelFormat::kYuyv && format != PixelFormat::kMjpeg;
}

bool is_bayer_mosaic(PixelFormat format) {
  return format == PixelFormat::kBayerRggb8 || format == PixelFormat::kBayerRggb16;
}

int bytes_per_pixel(PixelFormat format) {
  for (const auto& entry : kPixelFormats) {
    if (entry.format == format) return entry.bytes;
  }
  return 0;
}

std::string trigger_mode_name(TriggerMode mode) {
  switch (mode) {
    case TriggerMode::kFreeRun:
      return "free-run";
    case TriggerMode::kSoftware:
      return "software";
    case TriggerMode::kLine0:
      return "line0";
  }
  return "unknown";
}

std::optional<TriggerMode> trigger_mode_from_name(const std::string& name) {
  for (auto mode : {TriggerMode::kFreeRun, TriggerMode::kSoftware, TriggerMode::kLine0}) {
    if (name == trigger_mode_name(mode)) return mode;
  }
  return std::nullopt;
}

std::vector<CameraBackend> camera_backends() {
  return builtin_backends();
}

std::unique_ptr<CameraSource> make_camera(const std::string& spec, const CameraContext& context,
                                          std::string& error) {
  const auto colon = spec.find(':');
  const std::string scheme = spec.substr(0, colon);
  const std::string argument = colon == std::string::npos ? "" : spec.substr(colon + 1);
  std::vector<std::string> known;
  for (const auto& backend : camera_backends()) {
    if (backend.scheme == scheme) {
      auto camera = backend.create(argument, context, error);
      if (!camera && error.empty()) error = "camera '" + spec + "': the backend refused it";
      return camera;
    }
    known.push_back(backend.scheme);
  }
  error = "camera '" + spec + "': unknown backend '" + scheme + "' (known:";
  for (const auto& name : known) error += " " + name;
  error += ")";
  return nullptr;
}

}  // namespace flutterscan::capture
