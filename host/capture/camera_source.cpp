#include "capture/camera_source.hpp"

#include <algorithm>
#include <array>
#include <mutex>
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

struct Registry {
  std::mutex mutex;
  std::vector<CameraBackend> backends;
  bool builtins_registered = false;
};

Registry& registry() {
  static Registry instance;
  return instance;
}

void add_locked(Registry& reg, CameraBackend backend) {
  auto same = std::find_if(reg.backends.begin(), reg.backends.end(),
                           [&](const CameraBackend& b) { return b.scheme == backend.scheme; });
  if (same != reg.backends.end()) {
    *same = std::move(backend);
  } else {
    reg.backends.push_back(std::move(backend));
  }
}

void register_builtins_locked(Registry& reg) {
  if (reg.builtins_registered) return;
  reg.builtins_registered = true;
  std::vector<CameraBackend> builtins;
#ifdef FLUTTERSCAN_HAVE_V4L2
  builtins.push_back(v4l2_camera_backend());
#endif
#ifdef FLUTTERSCAN_HAVE_ARAVIS
  builtins.push_back(aravis_camera_backend());
#endif
#ifdef FLUTTERSCAN_HAVE_LIBCAMERA
  builtins.push_back(libcamera_camera_backend());
#endif
  builtins.push_back(files_camera_backend());
  builtins.push_back(sim_camera_backend());
  // Backends registered explicitly before first use win over built-ins.
  for (auto& backend : builtins) {
    bool taken = std::any_of(reg.backends.begin(), reg.backends.end(),
                             [&](const CameraBackend& b) { return b.scheme == backend.scheme; });
    if (!taken) reg.backends.push_back(std::move(backend));
  }
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

void register_camera_backend(CameraBackend backend) {
  auto& reg = registry();
  std::lock_guard lock(reg.mutex);
  add_locked(reg, std::move(backend));
}

std::vector<CameraBackend> camera_backends() {
  auto& reg = registry();
  std::lock_guard lock(reg.mutex);
  register_builtins_locked(reg);
  return reg.backends;
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
