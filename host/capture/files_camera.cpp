#include "capture/files_camera.hpp"

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "capture/backends.hpp"
#include "capture/host_clock.hpp"
#include "imaging/capture_descriptor.hpp"

namespace flutterscan::capture {
namespace {

namespace fs = std::filesystem;

constexpr std::int64_t kDefaultFramePeriodNs = 33'333'333;

bool is_image(const fs::path& path) {
  const std::string ext = path.extension().string();
  return ext == ".png" || ext == ".tif" || ext == ".tiff";
}

class FilesCamera final : public CameraSource {
 public:
  explicit FilesCamera(std::string folder) : folder_(std::move(folder)) {}

  std::string name() const override { return "files:" + folder_; }

  std::string open() override {
    std::error_code error;
    if (!fs::is_directory(folder_, error))
      return "camera files:" + folder_ + ": '" + folder_ + "' is not a folder";
    for (const auto& entry : fs::directory_iterator(folder_, error)) {
      const fs::path path = entry.path();
      if (!entry.is_regular_file() || !is_image(path)) continue;
      fs::path descriptor = path;
      descriptor.replace_extension(".json");
      if (fs::exists(descriptor)) frames_.push_back(path.string());
    }
    if (error)
      return "camera files:" + folder_ + ": cannot list '" + folder_ + "': " + error.message();
    std::sort(frames_.begin(), frames_.end());
    if (frames_.empty())
      return "camera files:" + folder_ +
             ": no frame with a descriptor (IMAGE.png + IMAGE.json) in '" + folder_ + "'";
    std::string problem;
    Frame first;
    if (!load(0, first, problem)) return problem;
    format_ = first.format;
    return {};
  }

  std::string configure(const CameraSettings& wanted) override {
    // Recorded frames cannot change: a request for another size or format is refused.
    if ((wanted.width && *wanted.width != format_.width) ||
        (wanted.height && *wanted.height != format_.height))
      return "camera " + name() + ": size " + std::to_string(wanted.width.value_or(format_.width)) +
             "x" + std::to_string(wanted.height.value_or(format_.height)) +
             " asked for, the recorded frames are " + std::to_string(format_.width) + "x" +
             std::to_string(format_.height);
    if (wanted.pixel_format && *wanted.pixel_format != format_.pixel_format)
      return "camera " + name() + ": pixel format " + pixel_format_name(*wanted.pixel_format) +
             " asked for, the recorded frames are " + pixel_format_name(format_.pixel_format);
    settings_ = CameraSettings{};
    settings_.width = format_.width;
    settings_.height = format_.height;
    settings_.pixel_format = format_.pixel_format;
    settings_.trigger = wanted.trigger;
    return {};
  }

  CameraSettings settings() const override { return settings_; }
  FrameFormat format() const override { return format_; }

  std::string start() override {
    if (frames_.empty()) return "camera " + name() + ": not opened";
    next_ = 0;
    counters_ = {};
    last_sequence_.reset();
    return {};
  }

  FrameWait next_frame(Frame& frame, std::chrono::milliseconds, std::string& error) override {
    if (next_ >= frames_.size()) return FrameWait::kEnd;
    if (!load(next_, frame, error)) return FrameWait::kError;
    ++next_;
    if (last_sequence_ && frame.sequence > *last_sequence_ + 1)
      counters_.frames_dropped += frame.sequence - *last_sequence_ - 1;
    last_sequence_ = frame.sequence;
    ++counters_.frames_delivered;
    return FrameWait::kFrame;
  }

  void stop() override { next_ = frames_.size(); }
  CameraCounters counters() const override { return counters_; }
  bool live() const override { return false; }

 private:
  bool load(std::size_t index, Frame& frame, std::string& error) const {
    const std::string& path = frames_[index];
    fs::path descriptor_path = path;
    descriptor_path.replace_extension(".json");
    std::ifstream in(descriptor_path);
    nlohmann::json descriptor = nlohmann::json::parse(in, nullptr, false);
    if (descriptor.is_discarded() || !descriptor.is_object()) {
      error = "camera " + name() + ": '" + descriptor_path.string() + "' is not a JSON object";
      return false;
    }
    const auto recorded = imaging::recorded_frame_from_descriptor(descriptor);
    if (!recorded.ok()) {
      error = "camera " + name() + ": '" + descriptor_path.string() + "': " + recorded.error();
      return false;
    }
    const imaging::RecordedFrame& r = recorded.value();
    cv::Mat mat = cv::imread(path, cv::IMREAD_UNCHANGED);
    if (mat.empty()) {
      error = "camera " + name() + ": cannot read '" + path + "'";
      return false;
    }
    if ((mat.depth() != CV_8U && mat.depth() != CV_16U) ||
        (mat.channels() != 1 && mat.channels() != 3)) {
      error = "camera " + name() + ": '" + path + "' is not an 8- or 16-bit grey or RGB image";
      return false;
    }
    if (mat.channels() == 3) cv::cvtColor(mat, mat, cv::COLOR_BGR2RGB);
    const bool wide = mat.depth() == CV_16U;
    frame.format.width = mat.cols;
    frame.format.height = mat.rows;
    if (mat.channels() == 3)
      frame.format.pixel_format = wide ? PixelFormat::kRgb16 : PixelFormat::kRgb8;
    else if (r.bayer_rggb)
      frame.format.pixel_format = wide ? PixelFormat::kBayerRggb16 : PixelFormat::kBayerRggb8;
    else
      frame.format.pixel_format = wide ? PixelFormat::kMono16 : PixelFormat::kMono8;
    frame.format.bit_depth = r.bit_depth.value_or(wide ? 16 : 8);
    frame.format.row_bytes = mat.cols * mat.elemSize();
    frame.data.resize(frame.format.row_bytes * static_cast<std::size_t>(mat.rows));
    for (int y = 0; y < mat.rows; ++y)
      std::copy(mat.ptr<std::uint8_t>(y), mat.ptr<std::uint8_t>(y) + frame.format.row_bytes,
                frame.data.data() + frame.format.row_bytes * static_cast<std::size_t>(y));
    frame.sequence = r.sequence.value_or(index);
    frame.timestamp_ns =
        r.timestamp_ns.value_or(static_cast<std::int64_t>(index) * kDefaultFramePeriodNs);
    frame.truth = r.truth;
    frame.truth_in_view = r.truth_in_view;
    frame.host_arrival_ns = host_now_ns();
    frame.descriptor_json = descriptor.dump();
    return true;
  }

  std::string folder_;
  std::vector<std::string> frames_;
  std::size_t next_ = 0;
  FrameFormat format_;
  CameraSettings settings_;
  CameraCounters counters_;
  std::optional<std::uint64_t> last_sequence_;
};

}  // namespace

std::unique_ptr<CameraSource> make_files_camera(const std::string& folder) {
  return std::make_unique<FilesCamera>(folder);
}

CameraBackend files_camera_backend() {
  CameraBackend backend;
  backend.scheme = "files";
  backend.summary = "files:DIR replays a folder of frames with capture descriptors";
  backend.create = [](const std::string& argument, const CameraContext&, std::string& error) {
    if (argument.empty()) {
      error = "camera 'files': give the folder, e.g. files:sessions/run1/frames";
      return std::unique_ptr<CameraSource>();
    }
    return make_files_camera(argument);
  };
  backend.list = [] { return std::vector<CameraInfo>{}; };
  return backend;
}

}  // namespace flutterscan::capture
