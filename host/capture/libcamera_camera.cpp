// "libcamera:ID": cameras through libcamera (Debian 12's 0.0.3). Built only
// with -DFLUTTERSCAN_LIBCAMERA=ON and compile-tested only: 0.0.3 has no
// virtual camera, and its API changes at every 0.x release (docs/session.md).
//
// Raw role (RGGB 8/10/12 unpacked) or RGB888/BGR888; AeEnable and AwbEnable
// off, ExposureTime and AnalogueGain set, on every request. libcamera 0.0.3
// cannot read controls back before the first frame, so configure() keeps what
// was asked and start() warns that auto exposure and white balance were only
// requested off (their read-back arrives with each frame's metadata).

#include <libcamera/libcamera.h>

#include <sys/mman.h>

#include <cmath>
#include <condition_variable>
#include <deque>
#include <mutex>

#include "capture/backends.hpp"

namespace flutterscan::capture {
namespace {

std::int64_t steady_now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

struct FormatMapping {
  libcamera::PixelFormat libcamera;
  PixelFormat format;
  int bit_depth;
};

const std::vector<FormatMapping>& mappings() {
  // DRM fourcc RGB888 is B, G, R in memory; BGR888 is R, G, B.
  static const std::vector<FormatMapping> kMappings = {
      {libcamera::formats::SRGGB8, PixelFormat::kBayerRggb8, 8},
      {libcamera::formats::SRGGB10, PixelFormat::kBayerRggb16, 10},
      {libcamera::formats::SRGGB12, PixelFormat::kBayerRggb16, 12},
      {libcamera::formats::RGB888, PixelFormat::kBgr8, 8},
      {libcamera::formats::BGR888, PixelFormat::kRgb8, 8},
      {libcamera::formats::R8, PixelFormat::kMono8, 8},
  };
  return kMappings;
}

class LibcameraCamera final : public CameraSource {
 public:
  explicit LibcameraCamera(std::string id) : id_(std::move(id)) {}
  ~LibcameraCamera() override {
    stop();
    if (camera_) camera_->release();
    camera_.reset();
    if (manager_) manager_->stop();
  }

  std::string name() const override { return "libcamera:" + id_; }

  std::string open() override {
    manager_ = std::make_unique<libcamera::CameraManager>();
    if (manager_->start() != 0)
      return "camera " + name() + ": libcamera's camera manager did not start";
    camera_ = manager_->get(id_);
    if (!camera_) return "camera " + name() + ": no such camera (flutterscan cameras lists them)";
    if (camera_->acquire() != 0) return "camera " + name() + ": in use by another process";
    return {};
  }

  std::string configure(const CameraSettings& wanted) override {
    if (!camera_) return "camera " + name() + ": not opened";
    const bool raw = !wanted.pixel_format || *wanted.pixel_format == PixelFormat::kBayerRggb8 ||
                     *wanted.pixel_format == PixelFormat::kBayerRggb16;
    config_ = camera_->generateConfiguration(
        {raw ? libcamera::StreamRole::Raw : libcamera::StreamRole::StillCapture});
    if (!config_ || config_->empty()) return "camera " + name() + ": no configuration for the role";
    libcamera::StreamConfiguration& stream = config_->at(0);
    if (wanted.pixel_format) {
      for (const auto& m : mappings())
        if (m.format == *wanted.pixel_format) stream.pixelFormat = m.libcamera;
    }
    if (wanted.width) stream.size.width = static_cast<unsigned>(*wanted.width);
    if (wanted.height) stream.size.height = static_cast<unsigned>(*wanted.height);
    if (config_->validate() == libcamera::CameraConfiguration::Invalid)
      return "camera " + name() + ": the configuration is invalid";
    if (camera_->configure(config_.get()) != 0) return "camera " + name() + ": configure failed";
    const FormatMapping* m = nullptr;
    for (const auto& candidate : mappings())
      if (candidate.libcamera == stream.pixelFormat) m = &candidate;
    if (m == nullptr)
      return "camera " + name() + ": pixel format " + stream.pixelFormat.toString() +
             " is not one flutterscan reads (SRGGB8/10/12, RGB888, BGR888, R8)";
    format_ = {static_cast<int>(stream.size.width), static_cast<int>(stream.size.height), m->format,
               m->bit_depth, stream.stride};
    settings_ = wanted;
    settings_.width = format_.width;
    settings_.height = format_.height;
    settings_.pixel_format = m->format;
    if (wanted.trigger != TriggerMode::kFreeRun)
      return "camera " + name() + ": libcamera has no trigger control: use trigger free-run";
    return {};
  }

  CameraSettings settings() const override { return settings_; }
  FrameFormat format() const override { return format_; }

  std::string start() override {
    if (!config_) return "camera " + name() + ": not configured";
    libcamera::Stream* stream = config_->at(0).stream();
    allocator_ = std::make_unique<libcamera::FrameBufferAllocator>(camera_);
    if (allocator_->allocate(stream) < 0) return "camera " + name() + ": cannot allocate buffers";
    for (const auto& buffer : allocator_->buffers(stream)) {
      auto request = camera_->createRequest();
      if (!request || request->addBuffer(stream, buffer.get()) != 0)
        return "camera " + name() + ": cannot create a request";
      apply_controls(request->controls());
      requests_.push_back(std::move(request));
    }
    camera_->requestCompleted.connect(this, &LibcameraCamera::on_completed);
    if (camera_->start() != 0) return "camera " + name() + ": start failed";
    running_ = true;
    for (auto& request : requests_) camera_->queueRequest(request.get());
    warnings_ = {"camera " + name() +
                 ": AeEnable and AwbEnable are requested off on every request; libcamera 0.0.3 "
                 "reports them only in frame metadata"};
    return {};
  }

  FrameWait next_frame(Frame& frame, std::chrono::milliseconds timeout,
                       std::string& error) override {
    std::unique_lock lock(mutex_);
    if (!ready_.wait_for(lock, timeout, [&] { return !completed_.empty(); }))
      return FrameWait::kTimeout;
    libcamera::Request* request = completed_.front();
    completed_.pop_front();
    lock.unlock();
    if (request->status() != libcamera::Request::RequestComplete) {
      ++counters_.incomplete_frames;
      ++counters_.frames_dropped;
      requeue(request);
      return FrameWait::kTimeout;
    }
    libcamera::FrameBuffer* buffer = request->buffers().begin()->second;
    const auto& metadata = buffer->metadata();
    if (last_sequence_ && metadata.sequence > *last_sequence_ + 1)
      counters_.frames_dropped += metadata.sequence - *last_sequence_ - 1;
    last_sequence_ = metadata.sequence;
    const auto& plane = buffer->planes()[0];
    void* memory =
        ::mmap(nullptr, plane.length, PROT_READ, MAP_SHARED, plane.fd.get(), plane.offset);
    if (memory == MAP_FAILED) {
      requeue(request);
      error = "camera " + name() + ": cannot map a frame buffer";
      return FrameWait::kError;
    }
    const auto* bytes = static_cast<const std::uint8_t*>(memory);
    frame.data.assign(bytes, bytes + plane.length);
    ::munmap(memory, plane.length);
    frame.sequence = metadata.sequence;
    frame.timestamp_ns = static_cast<std::int64_t>(metadata.timestamp);
    frame.host_arrival_ns = steady_now_ns();
    frame.format = format_;
    ++counters_.frames_delivered;
    requeue(request);
    return FrameWait::kFrame;
  }

  void stop() override {
    if (!running_) return;
    running_ = false;
    camera_->stop();
    camera_->requestCompleted.disconnect(this, &LibcameraCamera::on_completed);
    requests_.clear();
    allocator_.reset();
  }

  CameraCounters counters() const override { return counters_; }
  std::vector<std::string> warnings() const override { return warnings_; }

 private:
  void apply_controls(libcamera::ControlList& controls) const {
    controls.set(libcamera::controls::AeEnable, false);
    controls.set(libcamera::controls::AwbEnable, false);
    if (settings_.exposure_us)
      controls.set(libcamera::controls::ExposureTime,
                   static_cast<std::int32_t>(*settings_.exposure_us));
    if (settings_.gain_db)
      controls.set(libcamera::controls::AnalogueGain,
                   static_cast<float>(std::pow(10.0, *settings_.gain_db / 20.0)));
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

  std::string id_;
  std::unique_ptr<libcamera::CameraManager> manager_;
  std::shared_ptr<libcamera::Camera> camera_;
  std::unique_ptr<libcamera::CameraConfiguration> config_;
  std::unique_ptr<libcamera::FrameBufferAllocator> allocator_;
  std::vector<std::unique_ptr<libcamera::Request>> requests_;
  std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<libcamera::Request*> completed_;
  bool running_ = false;
  FrameFormat format_;
  CameraSettings settings_;
  CameraCounters counters_;
  std::optional<unsigned> last_sequence_;
  std::vector<std::string> warnings_;
};

}  // namespace

CameraBackend libcamera_camera_backend() {
  CameraBackend backend;
  backend.scheme = "libcamera";
  backend.summary = "libcamera:ID cameras through libcamera 0.0.3 (compile-tested only)";
  backend.create = [](const std::string& argument, const CameraContext&, std::string& error) {
    if (argument.empty()) {
      error = "camera 'libcamera': give the camera id (flutterscan cameras lists them)";
      return std::unique_ptr<CameraSource>();
    }
    return std::unique_ptr<CameraSource>(std::make_unique<LibcameraCamera>(argument));
  };
  backend.list = [] {
    std::vector<CameraInfo> found;
    libcamera::CameraManager manager;
    if (manager.start() != 0) return found;
    for (const auto& camera : manager.cameras()) {
      CameraInfo info;
      info.spec = "libcamera:" + camera->id();
      info.description = "libcamera camera";
      info.features = {"exposure", "analogue gain"};
      found.push_back(std::move(info));
    }
    manager.stop();
    return found;
  };
  return backend;
}

}  // namespace flutterscan::capture
