// "libcamera:ID": cameras through libcamera (Debian 12's 0.0.3; docs/capture.md). Run against
// the kernel's vimc driver through libcamera's vimc pipeline handler in a QEMU guest
// (test/vm/run_libcamera_vimc_vm.sh; what that does not reach is listed in docs/capture.md); the
// API changes at every 0.x release.
//
// One stream: the raw role when a Bayer format (or none) is asked for, else the still-capture
// role; RGGB 8/10/12 bit (unpacked), RGB888/BGR888 or R8. A format or size the pipeline changes
// is refused, as are exposure, gain or frame rate asked of a camera without the control and
// values outside its range. AeEnable and AwbEnable are set off on every request when the camera
// has them, ExposureTime, AnalogueGain and FrameDurationLimits when asked. libcamera 0.0.3
// cannot read controls back before the first frame, so configure() keeps what was asked and
// start() warns that the automatics were only requested off (or that the camera has none).

#include <libcamera/libcamera.h>
#include <sys/mman.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <condition_variable>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <map>
#include <mutex>
#include <sstream>

#include "capture/backends.hpp"
#include "capture/host_clock.hpp"

namespace flutterscan::capture {
namespace {

/// libcamera allows one CameraManager per process: the listing and every open camera share one,
/// started on first use and stopped when the last user lets go.
std::shared_ptr<libcamera::CameraManager> shared_manager(std::string& error) {
  static std::mutex mutex;
  static std::weak_ptr<libcamera::CameraManager> current;
  std::lock_guard lock(mutex);
  if (auto manager = current.lock()) return manager;
  // libcamera logs INFO and WARN lines to stderr by default (its version, sensors missing from
  // its database); flutterscan's output keeps errors only, unless the user chose the levels.
  ::setenv("LIBCAMERA_LOG_LEVELS", "*:ERROR", 0);
  auto started = std::make_unique<libcamera::CameraManager>();
  if (int ret = started->start(); ret != 0) {
    error = std::string("libcamera's camera manager did not start: ") + std::strerror(-ret);
    return nullptr;
  }
  auto manager =
      std::shared_ptr<libcamera::CameraManager>(started.release(), [](libcamera::CameraManager* m) {
        m->stop();
        delete m;
      });
  current = manager;
  return manager;
}

struct FormatMapping {
  libcamera::PixelFormat libcamera;
  PixelFormat format;
  int bit_depth;
};

/// Best first within each flutterscan format (the V4L2 backend's order: deepest Bayer first).
const std::vector<FormatMapping>& mappings() {
  // DRM fourcc RGB888 is B, G, R in memory; BGR888 is R, G, B.
  static const std::vector<FormatMapping> kMappings = {
      {libcamera::formats::SRGGB12, PixelFormat::kBayerRggb16, 12},
      {libcamera::formats::SRGGB10, PixelFormat::kBayerRggb16, 10},
      {libcamera::formats::SRGGB8, PixelFormat::kBayerRggb8, 8},
      {libcamera::formats::BGR888, PixelFormat::kRgb8, 8},
      {libcamera::formats::RGB888, PixelFormat::kBgr8, 8},
      {libcamera::formats::R8, PixelFormat::kMono8, 8},
  };
  return kMappings;
}

const FormatMapping* mapping_of(const libcamera::PixelFormat& format) {
  for (const auto& m : mappings())
    if (m.libcamera == format) return &m;
  return nullptr;
}

bool has_control(const libcamera::Camera& camera, const libcamera::ControlId& id) {
  return camera.controls().find(&id) != camera.controls().end();
}

/// Formats a stream configuration offers, as flutterscan names (those it reads), in order.
std::vector<std::string> offered_formats(const libcamera::StreamConfiguration& stream) {
  std::vector<std::string> names;
  for (const auto& format : stream.formats().pixelformats()) {
    const FormatMapping* m = mapping_of(format);
    if (m == nullptr) continue;
    std::string name = pixel_format_name(m->format);
    if (m->format == PixelFormat::kBayerRggb16) name += " (" + std::to_string(m->bit_depth) + ")";
    if (std::find(names.begin(), names.end(), name) == names.end()) names.push_back(name);
  }
  return names;
}

std::string control_range(const libcamera::ControlInfo& info) {
  // Appended piece by piece: "[" + string trips GCC 12's -Wrestrict false positive.
  std::string text(1, '[');
  text += info.min().toString();
  text += ", ";
  text += info.max().toString();
  text += ']';
  return text;
}

class LibcameraCamera final : public CameraSource {
 public:
  explicit LibcameraCamera(std::string id) : id_(std::move(id)) {}
  ~LibcameraCamera() override {
    stop();
    if (camera_ && acquired_) camera_->release();
    camera_.reset();
    manager_.reset();
  }

  std::string name() const override { return "libcamera:" + id_; }

  std::string open() override {
    std::string error;
    manager_ = shared_manager(error);
    if (!manager_) return "camera " + name() + ": " + error;
    camera_ = manager_->get(id_);
    if (!camera_) return "camera " + name() + ": no such camera (flutterscan cameras lists them)";
    if (camera_->acquire() != 0) return "camera " + name() + ": in use by another process";
    acquired_ = true;
    return {};
  }

  std::string configure(const CameraSettings& wanted) override {
    if (!camera_) return "camera " + name() + ": not opened";
    if (wanted.trigger != TriggerMode::kFreeRun)
      return "camera " + name() + ": libcamera has no trigger control: use trigger free-run";
    const bool raw = !wanted.pixel_format || is_bayer_mosaic(*wanted.pixel_format);
    config_ = camera_->generateConfiguration(
        {raw ? libcamera::StreamRole::Raw : libcamera::StreamRole::StillCapture});
    if (!config_ || config_->empty()) return "camera " + name() + ": no configuration for the role";
    libcamera::StreamConfiguration& stream = config_->at(0);
    if (wanted.pixel_format) {
      // The best of the camera's formats that gives the flutterscan format asked for.
      const auto offered = stream.formats().pixelformats();
      const FormatMapping* chosen = nullptr;
      for (const auto& m : mappings())
        if (m.format == *wanted.pixel_format && chosen == nullptr &&
            std::find(offered.begin(), offered.end(), m.libcamera) != offered.end())
          chosen = &m;
      if (chosen == nullptr) {
        std::string names;
        for (const auto& n : offered_formats(stream)) names += (names.empty() ? "" : ", ") + n;
        return "camera " + name() + ": pixel format " + pixel_format_name(*wanted.pixel_format) +
               " is not offered (it offers " + (names.empty() ? "none flutterscan reads" : names) +
               ")";
      }
      stream.pixelFormat = chosen->libcamera;
    } else if (mapping_of(stream.pixelFormat) == nullptr) {
      // The role's default is one flutterscan does not read (e.g. packed CSI-2 Bayer): the best
      // offered that it reads, if any.
      const auto offered = stream.formats().pixelformats();
      for (const auto& m : mappings())
        if (std::find(offered.begin(), offered.end(), m.libcamera) != offered.end()) {
          stream.pixelFormat = m.libcamera;
          break;
        }
    }
    if (wanted.width) stream.size.width = static_cast<unsigned>(*wanted.width);
    if (wanted.height) stream.size.height = static_cast<unsigned>(*wanted.height);
    const libcamera::PixelFormat asked_format = stream.pixelFormat;
    const libcamera::Size asked_size = stream.size;
    if (config_->validate() == libcamera::CameraConfiguration::Invalid)
      return "camera " + name() + ": libcamera finds the configuration " + stream.toString() +
             " invalid";
    if (wanted.pixel_format && stream.pixelFormat != asked_format)
      return "camera " + name() + ": pixel format " + asked_format.toString() +
             " asked, the pipeline set " + stream.pixelFormat.toString();
    if ((wanted.width || wanted.height) && stream.size != asked_size)
      return "camera " + name() + ": size " + asked_size.toString() + " asked, the pipeline set " +
             stream.size.toString();
    const FormatMapping* m = mapping_of(stream.pixelFormat);
    if (m == nullptr)
      return "camera " + name() + ": pixel format " + stream.pixelFormat.toString() +
             " is not one flutterscan reads (SRGGB8/10/12, RGB888, BGR888, R8)";
    if (auto problem = check_controls(wanted); !problem.empty()) return problem;
    if (int ret = camera_->configure(config_.get()); ret != 0)
      return "camera " + name() + ": configure " + stream.toString() +
             " failed: " + std::strerror(-ret);
    format_ = {static_cast<int>(stream.size.width), static_cast<int>(stream.size.height), m->format,
               m->bit_depth, stream.stride};
    if (format_.row_bytes == 0)  // a pipeline that leaves the stride unset: rows packed
      format_.row_bytes = static_cast<std::size_t>(format_.width) * bytes_per_pixel(m->format);
    settings_ = wanted;
    settings_.width = format_.width;
    settings_.height = format_.height;
    settings_.pixel_format = m->format;
    return {};
  }

  CameraSettings settings() const override { return settings_; }
  FrameFormat format() const override { return format_; }

  std::string start() override {
    if (!config_ || format_.width == 0) return "camera " + name() + ": not configured";
    libcamera::Stream* stream = config_->at(0).stream();
    allocator_ = std::make_unique<libcamera::FrameBufferAllocator>(camera_);
    if (allocator_->allocate(stream) < 0) return "camera " + name() + ": cannot allocate buffers";
    for (const auto& buffer : allocator_->buffers(stream)) {
      // Map each buffer once; frames are copied out of the mapping.
      const auto& plane = buffer->planes()[0];
      const std::size_t length = plane.offset + plane.length;
      void* memory = ::mmap(nullptr, length, PROT_READ, MAP_SHARED, plane.fd.get(), 0);
      if (memory == MAP_FAILED) {
        release_buffers();
        return "camera " + name() + ": cannot map a frame buffer: " + std::strerror(errno);
      }
      mappings_[buffer.get()] = {static_cast<std::uint8_t*>(memory), length, plane.offset};
      auto request = camera_->createRequest();
      if (!request || request->addBuffer(stream, buffer.get()) != 0) {
        release_buffers();
        return "camera " + name() + ": cannot create a request";
      }
      apply_controls(request->controls());
      requests_.push_back(std::move(request));
    }
    camera_->requestCompleted.connect(this, &LibcameraCamera::on_completed);
    if (int ret = camera_->start(); ret != 0) {
      camera_->requestCompleted.disconnect(this, &LibcameraCamera::on_completed);
      release_buffers();
      return "camera " + name() + ": start failed: " + std::strerror(-ret);
    }
    running_ = true;
    last_sequence_.reset();
    counters_ = {};
    for (auto& request : requests_) {
      if (int ret = camera_->queueRequest(request.get()); ret != 0) {
        stop();
        return "camera " + name() + ": queueing a request failed: " + std::strerror(-ret);
      }
    }
    return {};
  }

  FrameWait next_frame(Frame& frame, std::chrono::milliseconds timeout,
                       std::string& error) override {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (true) {
      std::unique_lock lock(mutex_);
      if (!ready_.wait_until(lock, deadline, [&] { return !completed_.empty(); }))
        return FrameWait::kTimeout;
      libcamera::Request* request = completed_.front();
      completed_.pop_front();
      lock.unlock();
      libcamera::FrameBuffer* buffer = request->buffers().begin()->second;
      const libcamera::FrameMetadata& metadata = buffer->metadata();
      count_sequence(metadata.sequence);
      const std::size_t image_bytes = format_.row_bytes * static_cast<std::size_t>(format_.height);
      if (request->status() != libcamera::Request::RequestComplete ||
          metadata.status != libcamera::FrameMetadata::FrameSuccess || metadata.planes().empty() ||
          metadata.planes()[0].bytesused < image_bytes) {
        // Broken or short: counted and not delivered; wait on for the next one.
        ++counters_.incomplete_frames;
        ++counters_.frames_dropped;
        requeue(request);
        continue;
      }
      const Mapping& mapping = mappings_.at(buffer);
      if (mapping.length < mapping.offset + image_bytes) {
        requeue(request);
        error = "camera " + name() + ": a frame buffer is smaller than the image";
        return FrameWait::kError;
      }
      const std::uint8_t* bytes = mapping.data + mapping.offset;
      frame.data.assign(bytes, bytes + image_bytes);
      frame.sequence = sequence64_;
      // SensorTimestamp (start of exposure of the first row) where the pipeline reports it, else
      // the buffer's timestamp.
      const auto sensor_ns = request->metadata().get(libcamera::controls::SensorTimestamp);
      frame.timestamp_ns = sensor_ns ? *sensor_ns : static_cast<std::int64_t>(metadata.timestamp);
      frame.host_arrival_ns = host_now_ns();
      frame.format = format_;
      ++counters_.frames_delivered;
      requeue(request);
      return FrameWait::kFrame;
    }
  }

  void stop() override {
    if (!running_) return;
    running_ = false;
    camera_->stop();
    camera_->requestCompleted.disconnect(this, &LibcameraCamera::on_completed);
    {
      std::lock_guard lock(mutex_);
      completed_.clear();
    }
    release_buffers();
  }

  CameraCounters counters() const override { return counters_; }
  std::vector<std::string> warnings() const override { return warnings_; }

 private:
  struct Mapping {
    std::uint8_t* data = nullptr;
    std::size_t length = 0;
    std::size_t offset = 0;
  };

  /// Refuses exposure, gain or frame rate the camera has no control for or cannot take; notes
  /// which automatics it has to turn off.
  std::string check_controls(const CameraSettings& wanted) {
    namespace c = libcamera::controls;
    const auto& info = camera_->controls();
    const auto refuse = [&](const std::string& what) { return "camera " + name() + ": " + what; };
    if (wanted.exposure_us) {
      auto it = info.find(&c::ExposureTime);
      if (it == info.end()) return refuse("exposure asked, but the camera has no ExposureTime");
      const auto us = static_cast<std::int32_t>(std::lround(*wanted.exposure_us));
      if (us < it->second.min().get<std::int32_t>() || us > it->second.max().get<std::int32_t>())
        return refuse("exposure " + std::to_string(us) + " us is outside ExposureTime " +
                      control_range(it->second) + " us");
    }
    if (wanted.gain_db) {
      auto it = info.find(&c::AnalogueGain);
      if (it == info.end()) return refuse("gain asked, but the camera has no AnalogueGain");
      const float gain = static_cast<float>(std::pow(10.0, *wanted.gain_db / 20.0));
      if (gain < it->second.min().get<float>() || gain > it->second.max().get<float>())
        return refuse("gain " + std::to_string(*wanted.gain_db) + " dB (x" + std::to_string(gain) +
                      ") is outside AnalogueGain " + control_range(it->second));
    }
    if (wanted.frame_rate_hz && !has_control(*camera_, c::FrameDurationLimits))
      return refuse("frame rate asked, but the camera has no FrameDurationLimits");
    warnings_.clear();
    const auto note = [&](const libcamera::ControlId& id, const char* what) {
      if (has_control(*camera_, id))
        warnings_.push_back("camera " + name() + ": " + what + " (" + id.name() +
                            ") is requested off on every request; libcamera 0.0.3 cannot read it "
                            "back before the first frame");
      else
        warnings_.push_back("camera " + name() + ": has no " + id.name() + " control: " + what +
                            " is neither turned off nor confirmed off");
    };
    note(c::AeEnable, "auto exposure and gain");
    note(c::AwbEnable, "auto white balance");
    return {};
  }

  void apply_controls(libcamera::ControlList& controls) const {
    namespace c = libcamera::controls;
    if (has_control(*camera_, c::AeEnable)) controls.set(c::AeEnable, false);
    if (has_control(*camera_, c::AwbEnable)) controls.set(c::AwbEnable, false);
    if (settings_.exposure_us)
      controls.set(c::ExposureTime, static_cast<std::int32_t>(std::lround(*settings_.exposure_us)));
    if (settings_.gain_db)
      controls.set(c::AnalogueGain, static_cast<float>(std::pow(10.0, *settings_.gain_db / 20.0)));
    if (settings_.frame_rate_hz) {
      const auto us = static_cast<std::int64_t>(std::lround(1e6 / *settings_.frame_rate_hz));
      controls.set(c::FrameDurationLimits, {us, us});
    }
  }

  /// Extends libcamera's 32-bit sequence to 64 bits and counts gaps as dropped frames.
  void count_sequence(std::uint32_t sequence) {
    if (last_sequence_) {
      const std::uint32_t step = sequence - *last_sequence_;  // wraps
      sequence64_ += step;
      if (step > 1) counters_.frames_dropped += step - 1;
    } else {
      sequence64_ = sequence;
    }
    last_sequence_ = sequence;
  }

  void on_completed(libcamera::Request* request) {
    if (request->status() == libcamera::Request::RequestCancelled) return;
    std::lock_guard lock(mutex_);
    completed_.push_back(request);
    ready_.notify_one();
  }

  void requeue(libcamera::Request* request) {
    if (!running_) return;
    request->reuse(libcamera::Request::ReuseBuffers);
    apply_controls(request->controls());
    camera_->queueRequest(request);
  }

  void release_buffers() {
    requests_.clear();
    for (const auto& [buffer, mapping] : mappings_) ::munmap(mapping.data, mapping.length);
    mappings_.clear();
    allocator_.reset();
  }

  std::string id_;
  std::shared_ptr<libcamera::CameraManager> manager_;
  std::shared_ptr<libcamera::Camera> camera_;
  bool acquired_ = false;
  std::unique_ptr<libcamera::CameraConfiguration> config_;
  std::unique_ptr<libcamera::FrameBufferAllocator> allocator_;
  std::map<const libcamera::FrameBuffer*, Mapping> mappings_;
  std::vector<std::unique_ptr<libcamera::Request>> requests_;
  std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<libcamera::Request*> completed_;
  bool running_ = false;
  FrameFormat format_;
  CameraSettings settings_;
  CameraCounters counters_;
  std::optional<std::uint32_t> last_sequence_;
  std::uint64_t sequence64_ = 0;
  std::vector<std::string> warnings_;
};

/// "Sensor B (vimc), external" and the like: the model and location libcamera knows.
std::string describe(const libcamera::Camera& camera) {
  namespace p = libcamera::properties;
  std::ostringstream text;
  const auto model = camera.properties().get(p::Model);
  text << (model ? *model : std::string("camera"));
  if (const auto location = camera.properties().get(p::Location)) {
    switch (*location) {
      case p::CameraLocationFront:
        text << ", front";
        break;
      case p::CameraLocationBack:
        text << ", back";
        break;
      case p::CameraLocationExternal:
        text << ", external";
        break;
      default:
        break;
    }
  }
  return text.str();
}

std::vector<std::string> describe_controls(const libcamera::Camera& camera) {
  namespace c = libcamera::controls;
  std::vector<std::string> features;
  const auto& info = camera.controls();
  if (auto it = info.find(&c::ExposureTime); it != info.end())
    features.push_back("exposure " + control_range(it->second) + " us");
  if (auto it = info.find(&c::AnalogueGain); it != info.end())
    features.push_back("analogue gain " + control_range(it->second));
  if (has_control(camera, c::FrameDurationLimits)) features.push_back("frame rate");
  if (has_control(camera, c::AeEnable)) features.push_back("auto exposure (turned off)");
  if (has_control(camera, c::AwbEnable)) features.push_back("auto white balance (turned off)");
  if (features.empty()) features.push_back("no exposure, gain or frame rate control");
  std::string others;
  for (const auto& [id, range] : info) {
    if (id == &c::ExposureTime || id == &c::AnalogueGain || id == &c::FrameDurationLimits ||
        id == &c::AeEnable || id == &c::AwbEnable)
      continue;
    others += (others.empty() ? "" : " ") + id->name();
  }
  if (!others.empty()) features.push_back("other controls: " + others);
  return features;
}

}  // namespace

CameraBackend libcamera_camera_backend() {
  CameraBackend backend;
  backend.scheme = "libcamera";
  backend.summary = "libcamera:ID cameras through libcamera 0.0.3";
  backend.create = [](const std::string& argument, const CameraContext&, std::string& error) {
    if (argument.empty()) {
      error = "camera 'libcamera': give the camera id (flutterscan cameras lists them)";
      return std::unique_ptr<CameraSource>();
    }
    return std::unique_ptr<CameraSource>(std::make_unique<LibcameraCamera>(argument));
  };
  backend.list = [] {
    std::vector<CameraInfo> found;
    std::string error;
    auto manager = shared_manager(error);
    if (!manager) return found;
    for (const auto& camera : manager->cameras()) {
      CameraInfo info;
      info.spec = "libcamera:" + camera->id();
      info.description = describe(*camera);
      // The raw role's formats and the processed ones, those flutterscan reads.
      for (auto role : {libcamera::StreamRole::Raw, libcamera::StreamRole::StillCapture}) {
        auto config = camera->generateConfiguration({role});
        if (!config || config->empty()) continue;
        for (const auto& name : offered_formats(config->at(0)))
          if (std::find(info.pixel_formats.begin(), info.pixel_formats.end(), name) ==
              info.pixel_formats.end())
            info.pixel_formats.push_back(name);
      }
      info.features = describe_controls(*camera);
      found.push_back(std::move(info));
    }
    return found;
  };
  return backend;
}

}  // namespace flutterscan::capture
