#include "capture/v4l2_source.hpp"

#include <linux/videodev2.h>

#include <algorithm>
#include <chrono>
#include <climits>
#include <filesystem>

#include "capture/backends.hpp"
#include "capture/host_clock.hpp"
#include "capture/v4l2_camera.hpp"

namespace flutterscan::capture {
namespace {

/// Backend options as parsed from key=value text.
struct V4l2Options {
  std::optional<std::int32_t> gain;
  std::optional<std::int32_t> gamma;
  V4l2IoMethod io = V4l2IoMethod::kAuto;
  int buffers = 4;
};

std::optional<long> parse_integer(const std::string& text) {
  if (text.empty()) return std::nullopt;
  std::size_t used = 0;
  try {
    const long value = std::stol(text, &used);
    if (used != text.size()) return std::nullopt;
    return value;
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

std::string parse_options(const std::string& name,
                          const std::vector<std::pair<std::string, std::string>>& options,
                          V4l2Options& out) {
  for (const auto& [key, value] : options) {
    const std::string where = name + ": option " + key + "=" + value;
    if (key == "gain" || key == "gamma") {
      const auto number = parse_integer(value);
      if (!number || *number < INT32_MIN || *number > INT32_MAX) {
        return where + ": not an integer in the driver's units";
      }
      (key == "gain" ? out.gain : out.gamma) = static_cast<std::int32_t>(*number);
    } else if (key == "io") {
      if (value == "auto") {
        out.io = V4l2IoMethod::kAuto;
      } else if (value == "mmap") {
        out.io = V4l2IoMethod::kMmap;
      } else if (value == "userptr") {
        out.io = V4l2IoMethod::kUserPtr;
      } else {
        return where + ": io is auto, mmap or userptr";
      }
    } else if (key == "buffers") {
      const auto number = parse_integer(value);
      if (!number || *number < 4 || *number > 32) return where + ": buffers is 4..32";
      out.buffers = static_cast<int>(*number);
    } else {
      return where + ": unknown (v4l2 options: gain, gamma, io, buffers)";
    }
  }
  return {};
}

class V4l2Source final : public CameraSource {
 public:
  V4l2Source(std::string device, V4l2Options options)
      : device_(std::move(device)), options_(options) {}

  std::string name() const override { return "v4l2:" + device_; }

  std::string open() override {
    auto opened = V4l2Camera::open(device_);
    if (!opened) return opened.error();
    camera_ = std::move(opened.value());
    return {};
  }

  std::string configure(const CameraSettings& wanted) override {
    if (!camera_) return name() + ": configure() before open()";
    if (wanted.trigger != TriggerMode::kFreeRun) {
      return name() + ": trigger " + trigger_mode_name(wanted.trigger) +
             " refused: V4L2 has no standard trigger control (free-run only)";
    }
    if (wanted.gain_db) {
      return name() +
             ": gain_db refused: V4L2 gains are in driver-specific units, not dB; set the v4l2 "
             "option gain=N instead";
    }
    if (wanted.auto_exposure || wanted.auto_gain || wanted.auto_white_balance ||
        wanted.gamma_or_tone_curve) {
      return name() +
             ": automatic exposure, gain, white balance or tone curves cannot be "
             "turned on: the linear model needs them off";
    }
    V4l2Config config;
    config.width = wanted.width.value_or(0);
    config.height = wanted.height.value_or(0);
    if (wanted.pixel_format) {
      config.fourccs = fourccs_for(*wanted.pixel_format);
      if (config.fourccs.empty()) {
        return name() + ": pixel format " + pixel_format_name(*wanted.pixel_format) +
               " has no V4L2 equivalent the backend accepts";
      }
    } else {
      for (const V4l2FormatInfo& info : v4l2_accepted_formats()) {
        if (pixel_format_of(info)) config.fourccs.push_back(info.fourcc);
      }
    }
    config.frame_rate = wanted.frame_rate_hz.value_or(0.0);
    config.controls.exposure_us = wanted.exposure_us;
    config.controls.gain = options_.gain;
    config.controls.gamma = options_.gamma;
    config.io = options_.io;
    config.buffer_count = options_.buffers;
    if (std::string error = camera_->configure(config); !error.empty()) return error;

    const V4l2Description& d = camera_->description();
    const std::optional<PixelFormat> pixel_format = pixel_format_of(d.format.info);
    if (!pixel_format) {
      return name() + ": pixel format " + std::string(d.format.info.name) +
             " cannot be passed on (raw Bayer must be RGGB)";
    }
    format_ = {};
    format_.width = d.format.width;
    format_.height = d.format.height;
    format_.pixel_format = *pixel_format;
    format_.bit_depth = d.format.info.bits_per_sample;
    format_.row_bytes = d.format.bytes_per_line;
    settings_ = {};
    settings_.width = d.format.width;
    settings_.height = d.format.height;
    settings_.pixel_format = *pixel_format;
    settings_.exposure_us = d.controls.exposure_us;
    if (d.format.frame_rate > 0.0) settings_.frame_rate_hz = d.format.frame_rate;
    return {};
  }

  CameraSettings settings() const override { return settings_; }
  FrameFormat format() const override { return format_; }

  std::string start() override {
    if (!camera_) return name() + ": start() before open()";
    last_sequence_.reset();
    runtime_warnings_.clear();
    return camera_->start();
  }

  FrameWait next_frame(Frame& frame, std::chrono::milliseconds timeout,
                       std::string& error) override {
    if (!camera_) {
      error = name() + ": next_frame() before open()";
      return FrameWait::kError;
    }
    V4l2Frame got;
    const V4l2Wait wait = camera_->next_frame(
        got,
        static_cast<int>(std::clamp<std::chrono::milliseconds::rep>(timeout.count(), 0, INT_MAX)),
        error);
    if (wait == V4l2Wait::kTimeout) return FrameWait::kTimeout;
    if (wait == V4l2Wait::kError) return FrameWait::kError;
    // Extend the 32-bit counter: the distance from the previous frame is 1 + the gap.
    const std::uint64_t sequence =
        last_sequence_ ? *last_sequence_ + 1 + got.dropped_before : got.sequence;
    last_sequence_ = sequence;
    frame = {};
    frame.sequence = sequence;
    frame.timestamp_ns = got.timestamp_ns;
    frame.format = format_;
    const std::size_t image_bytes =
        format_.pixel_format == PixelFormat::kMjpeg
            ? got.data.size()
            : std::min(got.data.size(),
                       format_.row_bytes * static_cast<std::size_t>(format_.height));
    frame.data.assign(got.data.begin(),
                      got.data.begin() + static_cast<std::ptrdiff_t>(image_bytes));
    frame.host_arrival_ns = host_now_ns();
    note_timestamp_kind(got);
    return FrameWait::kFrame;
  }

  void stop() override {
    if (camera_) camera_->stop();
  }

  CameraCounters counters() const override {
    CameraCounters counters;
    if (!camera_) return counters;
    const V4l2Stats& stats = camera_->stats();
    counters.frames_delivered = stats.frames;
    counters.frames_dropped = stats.dropped + stats.corrupt;
    counters.incomplete_frames = stats.corrupt;
    return counters;
  }

  std::vector<std::string> warnings() const override {
    std::vector<std::string> all;
    if (!camera_) return all;
    const V4l2Description& d = camera_->description();
    all.insert(all.end(), d.warnings.begin(), d.warnings.end());
    all.insert(all.end(), d.controls.warnings.begin(), d.controls.warnings.end());
    all.insert(all.end(), runtime_warnings_.begin(), runtime_warnings_.end());
    return all;
  }

 private:
  /// Warns once when timestamps are not start-of-exposure on the monotonic clock.
  void note_timestamp_kind(const V4l2Frame& frame) {
    if (frame.index != 0) return;
    if (frame.clock != V4l2Clock::kMonotonic) {
      runtime_warnings_.push_back(name() +
                                  ": buffer timestamps are not on the monotonic clock; matching "
                                  "frames to exposures by time is unreliable");
    }
    if (frame.timestamp_source == V4l2TimestampSource::kEndOfFrame) {
      runtime_warnings_.push_back(
          name() +
          ": the driver stamps the end of the frame, not the start of exposure; "
          "frame timestamps lag the exposure start by exposure plus readout time");
    }
  }

  std::string device_;
  V4l2Options options_;
  std::unique_ptr<V4l2Camera> camera_;
  CameraSettings settings_;
  FrameFormat format_;
  std::optional<std::uint64_t> last_sequence_;
  std::vector<std::string> runtime_warnings_;
};

}  // namespace

std::optional<PixelFormat> pixel_format_of(const V4l2FormatInfo& info) {
  switch (info.layout) {
    case V4l2Layout::kBayer:
      if (info.bayer_order != "RGGB") return std::nullopt;
      return info.bytes_per_sample == 1 ? PixelFormat::kBayerRggb8 : PixelFormat::kBayerRggb16;
    case V4l2Layout::kRgb:
      return PixelFormat::kRgb8;
    case V4l2Layout::kBgr:
      return PixelFormat::kBgr8;
    case V4l2Layout::kGrey:
      return info.bytes_per_sample == 1 ? PixelFormat::kMono8 : PixelFormat::kMono16;
    case V4l2Layout::kYuyv:
      return PixelFormat::kYuyv;
    case V4l2Layout::kMjpeg:
      return PixelFormat::kMjpeg;
  }
  return std::nullopt;
}

std::vector<std::uint32_t> fourccs_for(PixelFormat format) {
  std::vector<std::uint32_t> fourccs;
  for (const V4l2FormatInfo& info : v4l2_accepted_formats()) {
    if (pixel_format_of(info) == format) fourccs.push_back(info.fourcc);
  }
  return fourccs;
}

std::unique_ptr<CameraSource> make_v4l2_camera(
    const std::string& device, const std::vector<std::pair<std::string, std::string>>& options,
    std::string& error) {
  V4l2Options parsed;
  error = parse_options("v4l2:" + device, options, parsed);
  if (!error.empty()) return nullptr;
  return std::make_unique<V4l2Source>(device, parsed);
}

std::vector<CameraInfo> list_v4l2_cameras() {
  std::vector<CameraInfo> cameras;
  for (int n = 0; n < 64; ++n) {
    const std::string node = "/dev/video" + std::to_string(n);
    std::error_code ignored;
    if (!std::filesystem::exists(node, ignored)) continue;
    auto opened = V4l2Camera::open(node);
    if (!opened) continue;  // not a capture node (metadata, output, ...)
    const V4l2Camera& camera = *opened.value();
    const V4l2Description& d = camera.description();
    CameraInfo info;
    info.spec = "v4l2:" + node;
    info.description = d.card + " (" + d.driver + ", " + d.bus_info + ")";
    for (std::uint32_t fourcc : d.offered_fourccs) {
      const auto accepted = v4l2_format_info(fourcc);
      const auto pixel_format = accepted ? pixel_format_of(*accepted) : std::nullopt;
      if (!pixel_format) continue;
      const std::string name = pixel_format_name(*pixel_format);
      if (std::find(info.pixel_formats.begin(), info.pixel_formats.end(), name) ==
          info.pixel_formats.end()) {
        info.pixel_formats.push_back(name);
      }
    }
    info.features = camera.control_features();
    cameras.push_back(std::move(info));
  }
  return cameras;
}

CameraBackend v4l2_camera_backend() {
  CameraBackend backend;
  backend.scheme = "v4l2";
  backend.summary = "v4l2:/dev/videoN Linux V4L2 capture devices (UVC webcams, CSI sensors)";
  backend.create = [](const std::string& argument, const CameraContext& context,
                      std::string& error) -> std::unique_ptr<CameraSource> {
    if (argument.empty()) {
      error =
          "camera 'v4l2': give the device node, e.g. v4l2:/dev/video0 (flutterscan cameras "
          "lists them)";
      return nullptr;
    }
    return make_v4l2_camera(argument, context.options, error);
  };
  backend.list = list_v4l2_cameras;
  return backend;
}

}  // namespace flutterscan::capture
