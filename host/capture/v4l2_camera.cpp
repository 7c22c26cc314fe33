#include "capture/v4l2_camera.hpp"

#include <fcntl.h>
#include <linux/videodev2.h>
#include <poll.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>

#include "capture/v4l2_ioctl.hpp"

namespace flutterscan::capture {
namespace {

using OpenResult = Result<std::unique_ptr<V4l2Camera>, std::string>;

std::string errno_text() {
  return std::strerror(errno);
}

std::string join_fourccs(const std::vector<std::uint32_t>& fourccs) {
  std::string text;
  for (std::uint32_t f : fourccs) {
    if (!text.empty()) text += ' ';
    text += fourcc_text(f);
  }
  return text.empty() ? "none" : text;
}

/// Longest single poll() while waiting for a frame. A bounded slice, because
/// some nodes (umockdev's mocked ones) never report readiness: each slice
/// ends with a DQBUF attempt.
constexpr int kPollSliceMs = 100;

}  // namespace

const char* v4l2_io_method_name(V4l2IoMethod method) {
  switch (method) {
    case V4l2IoMethod::kAuto:
      return "auto";
    case V4l2IoMethod::kMmap:
      return "mmap";
    case V4l2IoMethod::kUserPtr:
      return "userptr";
  }
  return "?";
}

Result<std::unique_ptr<V4l2Camera>, std::string> V4l2Camera::open(const std::string& device) {
  const int fd = ::open(device.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return OpenResult::failure("cannot open " + device + ": " + errno_text());
  std::unique_ptr<V4l2Camera> camera(new V4l2Camera(fd, device));
  V4l2Description& description = camera->description_;

  v4l2_capability capability{};
  if (v4l2_ioctl(fd, VIDIOC_QUERYCAP, &capability) != 0) {
    return OpenResult::failure(device + " is not a V4L2 device (VIDIOC_QUERYCAP: " + errno_text() +
                               ")");
  }
  description.driver = reinterpret_cast<const char*>(capability.driver);
  description.card = reinterpret_cast<const char*>(capability.card);
  description.bus_info = reinterpret_cast<const char*>(capability.bus_info);
  const std::uint32_t caps = (capability.capabilities & V4L2_CAP_DEVICE_CAPS)
                                 ? capability.device_caps
                                 : capability.capabilities;
  if (!(caps & V4L2_CAP_VIDEO_CAPTURE)) {
    return OpenResult::failure(
        device + " (" + description.card + ") has no single-planar video capture" +
        ((caps & V4L2_CAP_VIDEO_CAPTURE_MPLANE) ? " (multi-planar devices are not supported)"
                                                : ""));
  }
  if (!(caps & V4L2_CAP_STREAMING)) {
    return OpenResult::failure(device + " (" + description.card +
                               ") does not support streaming I/O (read() only)");
  }

  for (std::uint32_t index = 0; index < 256; ++index) {
    v4l2_fmtdesc format{};
    format.index = index;
    format.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (v4l2_ioctl(fd, VIDIOC_ENUM_FMT, &format) != 0) break;
    description.offered_fourccs.push_back(format.pixelformat);
  }

  return OpenResult::success(std::move(camera));
}

std::string V4l2Camera::configure(const V4l2Config& config) {
  const std::string& device = device_;
  if (streaming_) return device + ": cannot configure while streaming";
  if (config.buffer_count < 4) {
    return device + ": buffer count " + std::to_string(config.buffer_count) +
           " is below the minimum of 4";
  }
  if (config.width < 0 || config.height < 0) {
    return device + ": negative frame size " + std::to_string(config.width) + "x" +
           std::to_string(config.height);
  }
  if (config.frame_rate < 0.0 || !std::isfinite(config.frame_rate)) {
    return device + ": frame rate " + std::to_string(config.frame_rate) +
           " is not a positive number";
  }
  configured_ = false;
  config_ = config;
  description_.format = {};
  description_.controls = {};
  description_.warnings.clear();
  if (std::string error = negotiate_format(); !error.empty()) return error;
  if (std::string error = set_frame_rate(); !error.empty()) return error;
  auto controls = apply_linear_controls(fd_, device, config.controls,
                                        description_.format.info.layout == V4l2Layout::kBayer);
  if (!controls) return controls.error();
  description_.controls = std::move(controls.value());
  configured_ = true;
  return {};
}

std::vector<std::string> V4l2Camera::control_features() const {
  return v4l2_control_features(fd_);
}

std::string V4l2Camera::negotiate_format() {
  const std::string& device = device_;
  const std::vector<std::uint32_t>& offered = description_.offered_fourccs;
  auto is_offered = [&](std::uint32_t f) {
    return std::find(offered.begin(), offered.end(), f) != offered.end();
  };
  std::optional<V4l2FormatInfo> chosen;
  if (!config_.fourccs.empty()) {
    for (std::uint32_t fourcc : config_.fourccs) {
      if (!v4l2_format_info(fourcc)) {
        return device + ": pixel format " + fourcc_text(fourcc) +
               " is not one the v4l2 backend accepts (raw Bayer 8/10/12/16, RGB24, BGR24, GREY, "
               "Y16, YUYV, MJPEG)";
      }
    }
    for (std::uint32_t fourcc : config_.fourccs) {
      if (is_offered(fourcc)) {
        chosen = v4l2_format_info(fourcc);
        break;
      }
    }
    if (!chosen) {
      return device + ": pixel format " + join_fourccs(config_.fourccs) +
             " is not offered (offers: " + join_fourccs(offered) + ")";
    }
  } else {
    for (const V4l2FormatInfo& info : v4l2_accepted_formats()) {
      if (is_offered(info.fourcc)) {
        chosen = info;
        break;
      }
    }
    if (!chosen) {
      return device +
             ": offers no pixel format the v4l2 backend accepts (offers: " + join_fourccs(offered) +
             ")";
    }
  }

  v4l2_format format{};
  format.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (v4l2_ioctl(fd_, VIDIOC_G_FMT, &format) != 0) {
    return device + ": cannot read the current format (VIDIOC_G_FMT: " + errno_text() + ")";
  }
  const int width = config_.width > 0 ? config_.width : static_cast<int>(format.fmt.pix.width);
  const int height = config_.height > 0 ? config_.height : static_cast<int>(format.fmt.pix.height);
  format = {};
  format.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  format.fmt.pix.width = static_cast<std::uint32_t>(width);
  format.fmt.pix.height = static_cast<std::uint32_t>(height);
  format.fmt.pix.pixelformat = chosen->fourcc;
  format.fmt.pix.field = V4L2_FIELD_NONE;
  if (v4l2_ioctl(fd_, VIDIOC_S_FMT, &format) != 0) {
    return device + ": cannot set format " + std::string(chosen->name) + " " +
           std::to_string(width) + "x" + std::to_string(height) +
           " (VIDIOC_S_FMT: " + errno_text() + ")";
  }
  const v4l2_pix_format& got = format.fmt.pix;
  if (got.pixelformat != chosen->fourcc) {
    return device + ": pixel format " + std::string(chosen->name) + " requested, driver set " +
           fourcc_text(got.pixelformat);
  }
  if (static_cast<int>(got.width) != width || static_cast<int>(got.height) != height) {
    return device + ": frame size " + std::to_string(width) + "x" + std::to_string(height) +
           " requested, driver set " + std::to_string(got.width) + "x" + std::to_string(got.height);
  }
  if (got.field != V4L2_FIELD_NONE && got.field != V4L2_FIELD_ANY) {
    return device + ": driver delivers interlaced fields (field order " +
           std::to_string(got.field) + "); only progressive frames are accepted";
  }
  V4l2Format& out = description_.format;
  out.info = *chosen;
  out.width = width;
  out.height = height;
  const std::uint32_t packed_line =
      static_cast<std::uint32_t>(width) * static_cast<std::uint32_t>(chosen->bytes_per_sample) *
      (chosen->layout == V4l2Layout::kRgb || chosen->layout == V4l2Layout::kBgr ? 3u
       : chosen->layout == V4l2Layout::kYuyv                                    ? 2u
                                                                                : 1u);
  out.bytes_per_line =
      chosen->layout == V4l2Layout::kMjpeg ? 0 : std::max(got.bytesperline, packed_line);
  out.image_size = got.sizeimage;
  if (out.image_size == 0) out.image_size = out.bytes_per_line * got.height;
  if (out.image_size == 0) {
    return device + ": driver reports no image size for " + std::string(chosen->name);
  }
  if (chosen->layout != V4l2Layout::kMjpeg && out.image_size < out.bytes_per_line * got.height) {
    return device + ": driver reports an image size of " + std::to_string(out.image_size) +
           " bytes, less than " + std::to_string(out.bytes_per_line) + " x " +
           std::to_string(got.height) + " lines";
  }
  if (!chosen->accuracy_loss.empty()) {
    description_.warnings.push_back(device + ": pixel format " + std::string(chosen->name) + ": " +
                                    std::string(chosen->accuracy_loss));
  }
  return {};
}

std::string V4l2Camera::set_frame_rate() {
  const std::string& device = device_;
  v4l2_streamparm parm{};
  parm.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  const bool readable = v4l2_ioctl(fd_, VIDIOC_G_PARM, &parm) == 0;
  const bool settable = readable && (parm.parm.capture.capability & V4L2_CAP_TIMEPERFRAME);
  if (config_.frame_rate > 0.0) {
    if (!settable) {
      return device + ": frame rate " + std::to_string(config_.frame_rate) +
             " fps requested but the driver cannot set the frame interval";
    }
    const double rate = config_.frame_rate;
    const bool whole = std::abs(rate - std::round(rate)) < 1e-9;
    parm = {};
    parm.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    parm.parm.capture.timeperframe.numerator = whole ? 1 : 1000;
    parm.parm.capture.timeperframe.denominator =
        static_cast<std::uint32_t>(std::llround(whole ? rate : rate * 1000.0));
    if (v4l2_ioctl(fd_, VIDIOC_S_PARM, &parm) != 0) {
      return device + ": cannot set frame rate " + std::to_string(rate) +
             " fps (VIDIOC_S_PARM: " + errno_text() + ")";
    }
    parm = {};
    parm.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (v4l2_ioctl(fd_, VIDIOC_G_PARM, &parm) != 0) {
      return device + ": cannot read the frame rate back (VIDIOC_G_PARM: " + errno_text() + ")";
    }
  }
  const v4l2_fract& interval = parm.parm.capture.timeperframe;
  const double got = (readable && interval.numerator > 0)
                         ? static_cast<double>(interval.denominator) / interval.numerator
                         : 0.0;
  if (config_.frame_rate > 0.0 && std::abs(got - config_.frame_rate) > 0.01 * config_.frame_rate) {
    return device + ": frame rate " + std::to_string(config_.frame_rate) +
           " fps requested, driver set " + std::to_string(got) + " fps";
  }
  description_.format.frame_rate = got;
  return {};
}

std::string V4l2Camera::start() {
  if (streaming_) return {};
  if (!configured_) return device_ + ": start() before a successful configure()";
  const std::string& device = device_;
  std::string error;
  io_in_use_ = V4l2IoMethod::kAuto;
  if (config_.io == V4l2IoMethod::kAuto || config_.io == V4l2IoMethod::kMmap) {
    error = request_mmap_buffers();
    if (error.empty()) {
      io_in_use_ = V4l2IoMethod::kMmap;
    } else if (config_.io == V4l2IoMethod::kAuto) {
      const std::string warning = error + "; streaming with USERPTR instead";
      std::vector<std::string>& warnings = description_.warnings;
      if (std::find(warnings.begin(), warnings.end(), warning) == warnings.end()) {
        warnings.push_back(warning);
      }
      error.clear();
    } else {
      return error;
    }
  }
  if (io_in_use_ != V4l2IoMethod::kMmap) {
    error = request_userptr_buffers();
    if (!error.empty()) return error;
    io_in_use_ = V4l2IoMethod::kUserPtr;
  }
  for (std::uint32_t i = 0; i < buffers_.size(); ++i) {
    if (std::string queue_error = queue_buffer(i); !queue_error.empty()) {
      release_buffers();
      return queue_error;
    }
  }
  int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (v4l2_ioctl(fd_, VIDIOC_STREAMON, &type) != 0) {
    const std::string reason = errno_text();
    release_buffers();
    return device + ": cannot start streaming (VIDIOC_STREAMON: " + reason + ")";
  }
  streaming_ = true;
  last_sequence_.reset();
  stats_ = {};
  return {};
}

std::string V4l2Camera::request_mmap_buffers() {
  const std::string& device = device_;
  v4l2_requestbuffers buffers{};
  buffers.count = static_cast<std::uint32_t>(config_.buffer_count);
  buffers.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  buffers.memory = V4L2_MEMORY_MMAP;
  if (v4l2_ioctl(fd_, VIDIOC_REQBUFS, &buffers) != 0) {
    return device + ": MMAP buffers refused (VIDIOC_REQBUFS: " + errno_text() + ")";
  }
  driver_memory_ = V4L2_MEMORY_MMAP;
  if (buffers.count < 2) {
    const std::string got = std::to_string(buffers.count);
    release_buffers();
    return device + ": driver gave only " + got + " MMAP buffer(s)";
  }
  buffers_.assign(buffers.count, Buffer{});
  for (std::uint32_t i = 0; i < buffers.count; ++i) {
    v4l2_buffer buffer{};
    buffer.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buffer.memory = V4L2_MEMORY_MMAP;
    buffer.index = i;
    if (v4l2_ioctl(fd_, VIDIOC_QUERYBUF, &buffer) != 0) {
      const std::string reason = errno_text();
      release_buffers();
      return device + ": cannot query MMAP buffer " + std::to_string(i) + " (" + reason + ")";
    }
    void* start =
        ::mmap(nullptr, buffer.length, PROT_READ | PROT_WRITE, MAP_SHARED, fd_, buffer.m.offset);
    if (start == MAP_FAILED) {
      const std::string reason = errno_text();
      release_buffers();
      return device + ": mmap of buffer " + std::to_string(i) + " failed (" + reason + ")";
    }
    buffers_[i] = {static_cast<std::uint8_t*>(start), buffer.length, true};
  }
  return {};
}

std::string V4l2Camera::request_userptr_buffers() {
  const std::string& device = device_;
  v4l2_requestbuffers buffers{};
  buffers.count = static_cast<std::uint32_t>(config_.buffer_count);
  buffers.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  buffers.memory = V4L2_MEMORY_USERPTR;
  if (v4l2_ioctl(fd_, VIDIOC_REQBUFS, &buffers) != 0) {
    return device + ": USERPTR buffers refused (VIDIOC_REQBUFS: " + errno_text() + ")";
  }
  driver_memory_ = V4L2_MEMORY_USERPTR;
  if (buffers.count < 2) {
    const std::string got = std::to_string(buffers.count);
    release_buffers();
    return device + ": driver accepts only " + got + " USERPTR buffer(s)";
  }
  const std::size_t page = static_cast<std::size_t>(::sysconf(_SC_PAGESIZE));
  const std::size_t length =
      (static_cast<std::size_t>(description_.format.image_size) + page - 1) / page * page;
  buffers_.assign(buffers.count, Buffer{});
  for (Buffer& buffer : buffers_) {
    buffer.start = static_cast<std::uint8_t*>(std::aligned_alloc(page, length));
    if (buffer.start == nullptr) {
      release_buffers();
      return device + ": cannot allocate " + std::to_string(length) + " bytes for a USERPTR buffer";
    }
    buffer.length = length;
  }
  return {};
}

std::string V4l2Camera::queue_buffer(std::uint32_t index) {
  v4l2_buffer buffer{};
  buffer.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  buffer.index = index;
  if (io_in_use_ == V4l2IoMethod::kUserPtr) {
    buffer.memory = V4L2_MEMORY_USERPTR;
    buffer.m.userptr = reinterpret_cast<unsigned long>(buffers_[index].start);
    buffer.length = static_cast<std::uint32_t>(buffers_[index].length);
  } else {
    buffer.memory = V4L2_MEMORY_MMAP;
  }
  if (v4l2_ioctl(fd_, VIDIOC_QBUF, &buffer) != 0) {
    return device_ + ": cannot queue buffer " + std::to_string(index) +
           " (VIDIOC_QBUF: " + errno_text() + ")";
  }
  return {};
}

V4l2Wait V4l2Camera::next_frame(V4l2Frame& frame, int timeout_ms, std::string& error) {
  const std::string& device = device_;
  if (!streaming_) {
    error = device + ": next_frame() before start()";
    return V4l2Wait::kError;
  }
  if (held_buffer_) {
    const std::uint32_t index = *held_buffer_;
    held_buffer_.reset();
    error = queue_buffer(index);
    if (!error.empty()) return V4l2Wait::kError;
  }
  using Clock = std::chrono::steady_clock;
  const auto deadline = Clock::now() + std::chrono::milliseconds(std::max(timeout_ms, 0));
  const V4l2Format& format = description_.format;
  const std::size_t min_bytes = static_cast<std::size_t>(format.bytes_per_line) * format.height;
  for (;;) {
    v4l2_buffer buffer{};
    buffer.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buffer.memory = io_in_use_ == V4l2IoMethod::kUserPtr ? V4L2_MEMORY_USERPTR : V4L2_MEMORY_MMAP;
    if (v4l2_ioctl(fd_, VIDIOC_DQBUF, &buffer) != 0) {
      if (errno != EAGAIN) {
        error = device + ": cannot dequeue a frame (VIDIOC_DQBUF: " + errno_text() + ")";
        return V4l2Wait::kError;
      }
      const auto left =
          std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
      if (left.count() <= 0) return V4l2Wait::kTimeout;
      pollfd waiting{fd_, POLLIN, 0};
      ::poll(&waiting, 1, static_cast<int>(std::min<long long>(left.count(), kPollSliceMs)));
      continue;
    }
    if (buffer.index >= buffers_.size()) {
      error = device + ": driver returned unknown buffer index " + std::to_string(buffer.index);
      return V4l2Wait::kError;
    }
    // Gaps in the driver's counter are frames the driver dropped.
    std::uint32_t gap = 0;
    if (last_sequence_) {
      const std::uint32_t expected = *last_sequence_ + 1;
      const std::uint32_t ahead = buffer.sequence - expected;  // modulo 2^32
      if (ahead < 0x80000000u) gap = ahead;
    }
    last_sequence_ = buffer.sequence;
    stats_.dropped += gap;
    const std::size_t used = buffer.bytesused != 0 ? buffer.bytesused : format.image_size;
    const bool short_frame = format.info.layout != V4l2Layout::kMjpeg && used < min_bytes;
    if ((buffer.flags & V4L2_BUF_FLAG_ERROR) || short_frame ||
        used > buffers_[buffer.index].length) {
      ++stats_.corrupt;
      error = queue_buffer(buffer.index);
      if (!error.empty()) return V4l2Wait::kError;
      continue;
    }
    frame = {};
    frame.data = {buffers_[buffer.index].start, used};
    frame.sequence = buffer.sequence;
    frame.timestamp_ns = static_cast<std::int64_t>(buffer.timestamp.tv_sec) * 1'000'000'000 +
                         static_cast<std::int64_t>(buffer.timestamp.tv_usec) * 1'000;
    switch (buffer.flags & V4L2_BUF_FLAG_TIMESTAMP_MASK) {
      case V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC:
        frame.clock = V4l2Clock::kMonotonic;
        break;
      case V4L2_BUF_FLAG_TIMESTAMP_COPY:
        frame.clock = V4l2Clock::kCopy;
        break;
      default:
        frame.clock = V4l2Clock::kUnknown;
        break;
    }
    frame.timestamp_source =
        (buffer.flags & V4L2_BUF_FLAG_TSTAMP_SRC_MASK) == V4L2_BUF_FLAG_TSTAMP_SRC_SOE
            ? V4l2TimestampSource::kStartOfExposure
            : V4l2TimestampSource::kEndOfFrame;
    frame.dropped_before = gap;
    frame.index = stats_.frames++;
    held_buffer_ = buffer.index;
    return V4l2Wait::kFrame;
  }
}

void V4l2Camera::stop() {
  if (streaming_) {
    int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    v4l2_ioctl(fd_, VIDIOC_STREAMOFF, &type);
    streaming_ = false;
  }
  held_buffer_.reset();
  release_buffers();
}

void V4l2Camera::release_buffers() {
  for (Buffer& buffer : buffers_) {
    if (buffer.start == nullptr) continue;
    if (buffer.mapped) {
      ::munmap(buffer.start, buffer.length);
    } else {
      std::free(buffer.start);
    }
  }
  buffers_.clear();
  // Free the driver's side too (count 0), so another memory type can be requested.
  v4l2_requestbuffers none{};
  none.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (driver_memory_) {
    none.memory = *driver_memory_;
    v4l2_ioctl(fd_, VIDIOC_REQBUFS, &none);
    driver_memory_.reset();
  }
}

V4l2Camera::~V4l2Camera() {
  stop();
  if (fd_ >= 0) ::close(fd_);
}

}  // namespace flutterscan::capture
