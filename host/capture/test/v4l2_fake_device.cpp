#include "v4l2_fake_device.hpp"

#include <umockdev.h>

#include <algorithm>
#include <cerrno>
#include <cstddef>
#include <cstring>
#include <stdexcept>

namespace flutterscan::capture::testing {
namespace {

gboolean on_ioctl(UMockdevIoctlBase*, UMockdevIoctlClient* client, gpointer device) {
  return static_cast<FakeV4l2Device*>(device)->handle(client) ? TRUE : FALSE;
}

void copy_name(std::uint8_t* out, std::size_t size, const std::string& text) {
  std::memset(out, 0, size);
  std::memcpy(out, text.data(), std::min(size - 1, text.size()));
}

std::uint32_t bytes_per_pixel(std::uint32_t fourcc) {
  switch (fourcc) {
    case V4L2_PIX_FMT_RGB24:
    case V4L2_PIX_FMT_BGR24:
      return 3;
    case V4L2_PIX_FMT_YUYV:
    case V4L2_PIX_FMT_SRGGB10:
    case V4L2_PIX_FMT_SRGGB12:
    case V4L2_PIX_FMT_SRGGB16:
    case V4L2_PIX_FMT_Y16:
      return 2;
    default:
      return 1;
  }
}

}  // namespace

std::vector<FakeControl> FakeDeviceConfig::default_controls() {
  return {
      {V4L2_CID_EXPOSURE_AUTO, "Auto Exposure", V4L2_CTRL_TYPE_MENU, 0, 3, 1,
       V4L2_EXPOSURE_APERTURE_PRIORITY, V4L2_EXPOSURE_APERTURE_PRIORITY, false},
      {V4L2_CID_EXPOSURE_ABSOLUTE, "Exposure Time, Absolute", V4L2_CTRL_TYPE_INTEGER, 1, 10000, 1,
       333, 333, false},
      {V4L2_CID_AUTOGAIN, "Gain, Automatic", V4L2_CTRL_TYPE_BOOLEAN, 0, 1, 1, 1, 1, false},
      {V4L2_CID_GAIN, "Gain", V4L2_CTRL_TYPE_INTEGER, 0, 255, 1, 32, 32, false},
      {V4L2_CID_AUTO_WHITE_BALANCE, "White Balance, Automatic", V4L2_CTRL_TYPE_BOOLEAN, 0, 1, 1, 1,
       1, false},
      {V4L2_CID_GAMMA, "Gamma", V4L2_CTRL_TYPE_INTEGER, 1, 500, 1, 100, 100, false},
  };
}

std::uint8_t pattern_byte(std::uint32_t sequence, std::size_t offset) {
  return static_cast<std::uint8_t>((offset * 7 + offset / 256 + sequence * 13) & 0xff);
}

FakeV4l2Device::FakeV4l2Device(FakeDeviceConfig config) : config_(std::move(config)) {
  format_.width = static_cast<std::uint32_t>(config_.initial_width);
  format_.height = static_cast<std::uint32_t>(config_.initial_height);
  format_.pixelformat = config_.formats.empty() ? V4L2_PIX_FMT_RGB24 : config_.formats.front();
  set_format(format_);
  if (!config_.frame_rates.empty()) frame_rate_ = config_.frame_rates.front();

  testbed_ = umockdev_testbed_new();
  // A video4linux device with its node; "N:" makes /dev/video0 in the testbed.
  const std::string record =
      "P: /devices/platform/fakecam/video4linux/video0\nN: video0\n"
      "E: SUBSYSTEM=video4linux\nE: DEVNAME=/dev/video0\n"
      "A: dev=81:0\nA: name=" +
      config_.card + "\n";
  GError* error = nullptr;
  if (!umockdev_testbed_add_from_string(testbed_, record.c_str(), &error)) {
    const std::string why = error ? error->message : "unknown error";
    g_clear_error(&error);
    throw std::runtime_error("umockdev: cannot add the fake /dev/video0: " + why);
  }
  handler_ = umockdev_ioctl_base_new();
  g_signal_connect(handler_, "handle-ioctl", G_CALLBACK(on_ioctl), this);
  if (!umockdev_testbed_attach_ioctl(testbed_, "/dev/video0", handler_, &error)) {
    const std::string why = error ? error->message : "unknown error";
    g_clear_error(&error);
    throw std::runtime_error("umockdev: cannot attach the V4L2 handler to /dev/video0: " + why);
  }
}

FakeV4l2Device::~FakeV4l2Device() {
  umockdev_testbed_detach_ioctl(testbed_, "/dev/video0", nullptr);
  g_object_unref(handler_);
  g_object_unref(testbed_);
}

std::optional<std::int32_t> FakeV4l2Device::control_value(std::uint32_t id) const {
  std::lock_guard lock(mutex_);
  for (const FakeControl& control : config_.controls) {
    if (control.id == id) return control.value;
  }
  return std::nullopt;
}

int FakeV4l2Device::buffer_requests(std::uint32_t memory) const {
  std::lock_guard lock(mutex_);
  const auto found = buffer_requests_.find(memory);
  return found == buffer_requests_.end() ? 0 : found->second;
}

bool FakeV4l2Device::streaming() const {
  std::lock_guard lock(mutex_);
  return streaming_;
}

bool FakeV4l2Device::handle(UMockdevIoctlClient* client) {
  const unsigned long request = umockdev_ioctl_client_get_request(client);
  if (_IOC_TYPE(request) != 'V' || _IOC_SIZE(request) == 0) {
    umockdev_ioctl_client_complete(client, -1, ENOTTY);
    return true;
  }
  // The argument arrives as the client's pointer; fetch the struct it points to.
  GError* resolve_error = nullptr;
  UMockdevIoctlData* arg = umockdev_ioctl_data_resolve(umockdev_ioctl_client_get_arg(client), 0,
                                                       _IOC_SIZE(request), &resolve_error);
  if (arg == nullptr) {
    g_clear_error(&resolve_error);
    umockdev_ioctl_client_complete(client, -1, EFAULT);
    return true;
  }
  int error = 0;
  long result;
  {
    std::lock_guard lock(mutex_);
    result = answer(request, arg->data, arg, error);
  }
  umockdev_ioctl_client_complete(client, result, error);
  umockdev_ioctl_data_unref(arg);
  return true;
}

void FakeV4l2Device::set_format(v4l2_pix_format& pix) {
  if (std::find(config_.formats.begin(), config_.formats.end(), pix.pixelformat) ==
      config_.formats.end()) {
    pix.pixelformat = config_.formats.front();
  }
  pix.width =
      std::clamp<std::uint32_t>(pix.width, 16, static_cast<std::uint32_t>(config_.max_width));
  pix.height =
      std::clamp<std::uint32_t>(pix.height, 16, static_cast<std::uint32_t>(config_.max_height));
  pix.field = V4L2_FIELD_NONE;
  pix.bytesperline = pix.width * bytes_per_pixel(pix.pixelformat);
  pix.sizeimage = pix.bytesperline * pix.height;
  pix.colorspace = V4L2_COLORSPACE_SRGB;
}

long FakeV4l2Device::answer(unsigned long request, void* arg, UMockdevIoctlData* data, int& error) {
  auto fail = [&error](int code) {
    error = code;
    return -1L;
  };
  switch (request) {
    case VIDIOC_QUERYCAP: {
      auto& cap = *static_cast<v4l2_capability*>(arg);
      std::memset(&cap, 0, sizeof cap);
      copy_name(cap.driver, sizeof cap.driver, "fakecam");
      copy_name(cap.card, sizeof cap.card, config_.card);
      copy_name(cap.bus_info, sizeof cap.bus_info, "umockdev:video0");
      cap.version = 0x060100;
      cap.device_caps = config_.device_caps;
      cap.capabilities = config_.device_caps | V4L2_CAP_DEVICE_CAPS;
      return 0;
    }
    case VIDIOC_ENUM_FMT: {
      auto& desc = *static_cast<v4l2_fmtdesc*>(arg);
      if (desc.type != V4L2_BUF_TYPE_VIDEO_CAPTURE || desc.index >= config_.formats.size()) {
        return fail(EINVAL);
      }
      desc.pixelformat = config_.formats[desc.index];
      desc.flags = desc.pixelformat == V4L2_PIX_FMT_MJPEG ? V4L2_FMT_FLAG_COMPRESSED : 0;
      copy_name(desc.description, sizeof desc.description, "fake format");
      return 0;
    }
    case VIDIOC_G_FMT: {
      auto& format = *static_cast<v4l2_format*>(arg);
      if (format.type != V4L2_BUF_TYPE_VIDEO_CAPTURE) return fail(EINVAL);
      format.fmt.pix = format_;
      return 0;
    }
    case VIDIOC_S_FMT:
    case VIDIOC_TRY_FMT: {
      auto& format = *static_cast<v4l2_format*>(arg);
      if (format.type != V4L2_BUF_TYPE_VIDEO_CAPTURE) return fail(EINVAL);
      if (request == VIDIOC_S_FMT && buffer_count_ > 0) return fail(EBUSY);
      set_format(format.fmt.pix);
      if (request == VIDIOC_S_FMT) format_ = format.fmt.pix;
      return 0;
    }
    case VIDIOC_G_PARM:
    case VIDIOC_S_PARM: {
      auto& parm = *static_cast<v4l2_streamparm*>(arg);
      if (parm.type != V4L2_BUF_TYPE_VIDEO_CAPTURE) return fail(EINVAL);
      if (request == VIDIOC_S_PARM && !config_.frame_rates.empty()) {
        const v4l2_fract& wanted = parm.parm.capture.timeperframe;
        const double fps = wanted.numerator ? double(wanted.denominator) / wanted.numerator : 30.0;
        // Nearest supported rate, as drivers do.
        frame_rate_ = *std::min_element(config_.frame_rates.begin(), config_.frame_rates.end(),
                                        [fps](std::uint32_t a, std::uint32_t b) {
                                          return std::abs(a - fps) < std::abs(b - fps);
                                        });
      }
      std::memset(&parm.parm, 0, sizeof parm.parm);
      if (!config_.frame_rates.empty()) {
        parm.parm.capture.capability = V4L2_CAP_TIMEPERFRAME;
        parm.parm.capture.timeperframe = {1, frame_rate_};
      }
      return 0;
    }
    case VIDIOC_QUERYCTRL: {
      auto& query = *static_cast<v4l2_queryctrl*>(arg);
      for (const FakeControl& control : config_.controls) {
        if (control.id != query.id) continue;
        query.type = control.type;
        copy_name(query.name, sizeof query.name, control.name);
        query.minimum = control.minimum;
        query.maximum = control.maximum;
        query.step = control.step;
        query.default_value = control.default_value;
        query.flags = 0;
        return 0;
      }
      return fail(EINVAL);
    }
    case VIDIOC_G_CTRL:
    case VIDIOC_S_CTRL: {
      auto& value = *static_cast<v4l2_control*>(arg);
      FakeControl* control = nullptr;
      for (FakeControl& c : config_.controls) {
        if (c.id == value.id) control = &c;
      }
      if (control == nullptr) return fail(EINVAL);
      if (request == VIDIOC_G_CTRL) {
        value.value = control->value;
        return 0;
      }
      if (value.value < control->minimum || value.value > control->maximum) return fail(ERANGE);
      if (control->id == V4L2_CID_EXPOSURE_ABSOLUTE) {
        // Manual exposure is inactive while auto exposure is on (UVC answers EBUSY too).
        for (const FakeControl& c : config_.controls) {
          if (c.id == V4L2_CID_EXPOSURE_AUTO && c.value != V4L2_EXPOSURE_MANUAL) return fail(EBUSY);
        }
      }
      if (!control->ignores_writes) control->value = value.value;
      return 0;
    }
    case VIDIOC_REQBUFS: {
      auto& buffers = *static_cast<v4l2_requestbuffers*>(arg);
      if (buffers.type != V4L2_BUF_TYPE_VIDEO_CAPTURE) return fail(EINVAL);
      if (buffers.memory != V4L2_MEMORY_MMAP && buffers.memory != V4L2_MEMORY_USERPTR) {
        return fail(EINVAL);
      }
      if (buffers.memory == V4L2_MEMORY_USERPTR && !config_.userptr_supported) return fail(EINVAL);
      if (streaming_) return fail(EBUSY);
      queue_.clear();
      if (buffers.count == 0) {
        buffer_count_ = 0;
        memory_ = 0;
        return 0;
      }
      ++buffer_requests_[buffers.memory];
      buffers.count = std::clamp<std::uint32_t>(buffers.count, 2, 32);
      buffer_count_ = buffers.count;
      memory_ = buffers.memory;
      return 0;
    }
    case VIDIOC_QUERYBUF: {
      auto& buffer = *static_cast<v4l2_buffer*>(arg);
      if (buffer.index >= buffer_count_ || memory_ != V4L2_MEMORY_MMAP) return fail(EINVAL);
      buffer.length = format_.sizeimage;
      buffer.m.offset = buffer.index * ((format_.sizeimage + 4095) / 4096 * 4096);
      buffer.flags = V4L2_BUF_FLAG_MAPPED;
      return 0;
    }
    case VIDIOC_QBUF: {
      auto& buffer = *static_cast<v4l2_buffer*>(arg);
      if (buffer.index >= buffer_count_ || buffer.memory != memory_) return fail(EINVAL);
      if (memory_ == V4L2_MEMORY_USERPTR &&
          (buffer.m.userptr == 0 || buffer.length < format_.sizeimage)) {
        return fail(EINVAL);
      }
      for (const QueuedBuffer& queued : queue_) {
        if (queued.index == buffer.index) return fail(EINVAL);
      }
      queue_.push_back({buffer.index, buffer.m.userptr, buffer.length});
      return 0;
    }
    case VIDIOC_DQBUF:
      return dequeue(*static_cast<v4l2_buffer*>(arg), data, error);
    case VIDIOC_STREAMON:
      if (buffer_count_ == 0) return fail(EINVAL);
      streaming_ = true;
      next_sequence_ = 0;  // drivers count from 0 at every stream start
      delivered_ = 0;
      return 0;
    case VIDIOC_STREAMOFF:
      streaming_ = false;
      queue_.clear();
      return 0;
    default:
      return fail(ENOTTY);
  }
}

long FakeV4l2Device::dequeue(v4l2_buffer& buffer, UMockdevIoctlData* data, int& error) {
  if (!streaming_ || buffer.memory != memory_) {
    error = EINVAL;
    return -1;
  }
  if (queue_.empty() || (config_.stall_after && delivered_ >= *config_.stall_after)) {
    error = EAGAIN;
    return -1;
  }
  if (memory_ != V4L2_MEMORY_USERPTR) {
    error = EIO;  // MMAP buffers cannot be filled through umockdev
    return -1;
  }
  const QueuedBuffer queued = queue_.front();
  queue_.erase(queue_.begin());
  const auto gap = config_.sequence_gaps.find(delivered_);
  if (gap != config_.sequence_gaps.end()) next_sequence_ += gap->second;
  const std::uint32_t sequence = next_sequence_++;

  buffer.index = queued.index;
  buffer.m.userptr = queued.userptr;
  buffer.length = queued.length;
  buffer.bytesused = format_.sizeimage;
  buffer.field = V4L2_FIELD_NONE;
  buffer.sequence = sequence;
  const std::int64_t ns = 1'000'000'000LL + sequence * config_.frame_interval_ns;
  buffer.timestamp.tv_sec = ns / 1'000'000'000;
  buffer.timestamp.tv_usec = (ns % 1'000'000'000) / 1000;
  buffer.flags =
      V4L2_BUF_FLAG_DONE | V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC | V4L2_BUF_FLAG_TSTAMP_SRC_SOE;
  if (config_.error_frames.count(delivered_)) buffer.flags |= V4L2_BUF_FLAG_ERROR;
  ++delivered_;

  // Write the frame into the client's own buffer.
  GError* resolve_error = nullptr;
  UMockdevIoctlData* memory = umockdev_ioctl_data_resolve(data, offsetof(v4l2_buffer, m.userptr),
                                                          queued.length, &resolve_error);
  if (memory == nullptr) {
    g_clear_error(&resolve_error);
    error = EFAULT;
    return -1;
  }
  for (std::size_t i = 0; i < format_.sizeimage; ++i) memory->data[i] = pattern_byte(sequence, i);
  umockdev_ioctl_data_unref(memory);
  return 0;
}

}  // namespace flutterscan::capture::testing
