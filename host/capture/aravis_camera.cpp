#include "capture/aravis_camera.hpp"

#include <arv.h>

#include <array>
#include <cstring>

#include "capture/backends.hpp"
#include "capture/host_clock.hpp"

namespace flutterscan::capture {
namespace {

constexpr int kStreamBuffers = 8;

struct FormatMapping {
  ArvPixelFormat arv;
  PixelFormat format;
  int bit_depth;
};

constexpr std::array<FormatMapping, 10> kFormats{{
    {ARV_PIXEL_FORMAT_MONO_8, PixelFormat::kMono8, 8},
    {ARV_PIXEL_FORMAT_MONO_10, PixelFormat::kMono16, 10},
    {ARV_PIXEL_FORMAT_MONO_12, PixelFormat::kMono16, 12},
    {ARV_PIXEL_FORMAT_MONO_16, PixelFormat::kMono16, 16},
    {ARV_PIXEL_FORMAT_RGB_8_PACKED, PixelFormat::kRgb8, 8},
    {ARV_PIXEL_FORMAT_BGR_8_PACKED, PixelFormat::kBgr8, 8},
    {ARV_PIXEL_FORMAT_BAYER_RG_8, PixelFormat::kBayerRggb8, 8},
    {ARV_PIXEL_FORMAT_BAYER_RG_10, PixelFormat::kBayerRggb16, 10},
    {ARV_PIXEL_FORMAT_BAYER_RG_12, PixelFormat::kBayerRggb16, 12},
    {ARV_PIXEL_FORMAT_BAYER_RG_16, PixelFormat::kBayerRggb16, 16},
}};

const FormatMapping* mapping_of(ArvPixelFormat arv) {
  for (const auto& m : kFormats)
    if (m.arv == arv) return &m;
  return nullptr;
}

std::string take_error(GError*& error) {
  std::string text = error != nullptr ? error->message : "unknown error";
  g_clear_error(&error);
  return text;
}

bool has_feature(ArvCamera* camera, const char* feature) {
  GError* error = nullptr;
  const bool available = arv_camera_is_feature_available(camera, feature, &error);
  g_clear_error(&error);
  return available;
}

class AravisCamera final : public CameraSource {
 public:
  explicit AravisCamera(std::string device_id) : device_id_(std::move(device_id)) {}
  ~AravisCamera() override {
    stop();
    if (camera_ != nullptr) g_object_unref(camera_);
  }

  std::string name() const override { return "aravis:" + device_id_; }

  std::string open() override {
    std::string id = device_id_;
    if (id == "fake") id = "Fake_1";
    if (id.rfind("Fake_", 0) == 0) arv_enable_interface("Fake");
    GError* error = nullptr;
    camera_ = arv_camera_new(id.c_str(), &error);
    if (camera_ == nullptr) return "camera " + name() + ": " + take_error(error);
    return read_back();
  }

  std::string configure(const CameraSettings& wanted) override {
    if (camera_ == nullptr) return "camera " + name() + ": not opened";
    GError* error = nullptr;
    auto failed = [&](const std::string& setting) {
      return "camera " + name() + ": cannot set " + setting + ": " + take_error(error);
    };
    if (wanted.pixel_format) {
      ArvPixelFormat arv = 0;
      for (const auto& m : kFormats)
        if (m.format == *wanted.pixel_format && arv == 0) arv = m.arv;
      if (arv == 0)
        return "camera " + name() + ": PixelFormat " + pixel_format_name(*wanted.pixel_format) +
               " has no GenICam equivalent here";
      arv_camera_set_pixel_format(camera_, arv, &error);
      if (error) return failed("PixelFormat " + pixel_format_name(*wanted.pixel_format));
    }
    if (wanted.width || wanted.height) {
      gint x = 0, y = 0, w = 0, h = 0;
      arv_camera_get_region(camera_, &x, &y, &w, &h, &error);
      if (error) return failed("the region");
      arv_camera_set_region(camera_, 0, 0, wanted.width.value_or(w), wanted.height.value_or(h),
                            &error);
      if (error) return failed("Width/Height");
    }
    if (arv_camera_is_exposure_auto_available(camera_, &error)) {
      arv_camera_set_exposure_time_auto(camera_, ARV_AUTO_OFF, &error);
      if (error) return failed("ExposureAuto Off");
    }
    g_clear_error(&error);
    if (arv_camera_is_gain_auto_available(camera_, &error)) {
      arv_camera_set_gain_auto(camera_, ARV_AUTO_OFF, &error);
      if (error) return failed("GainAuto Off");
    }
    g_clear_error(&error);
    if (has_feature(camera_, "BalanceWhiteAuto")) {
      arv_camera_set_string(camera_, "BalanceWhiteAuto", "Off", &error);
      if (error) return failed("BalanceWhiteAuto Off");
    }
    if (has_feature(camera_, "GammaEnable")) {
      arv_camera_set_boolean(camera_, "GammaEnable", false, &error);
      if (error) return failed("GammaEnable false");
    } else if (has_feature(camera_, "Gamma")) {
      arv_camera_set_float(camera_, "Gamma", 1.0, &error);
      if (error) return failed("Gamma 1");
    }
    if (has_feature(camera_, "LUTEnable")) {
      arv_camera_set_boolean(camera_, "LUTEnable", false, &error);
      if (error) return failed("LUTEnable false");
    }
    if (wanted.exposure_us) {
      arv_camera_set_exposure_time(camera_, *wanted.exposure_us, &error);
      if (error) return failed("ExposureTime " + std::to_string(*wanted.exposure_us) + " us");
    }
    if (wanted.gain_db) {
      arv_camera_set_gain(camera_, *wanted.gain_db, &error);
      if (error) return failed("Gain " + std::to_string(*wanted.gain_db));
    }
    switch (wanted.trigger) {
      case TriggerMode::kFreeRun:
        arv_camera_clear_triggers(camera_, &error);
        if (error) return failed("TriggerMode Off");
        if (wanted.frame_rate_hz) {
          arv_camera_set_frame_rate(camera_, *wanted.frame_rate_hz, &error);
          if (error) return failed("AcquisitionFrameRate " + std::to_string(*wanted.frame_rate_hz));
        }
        break;
      case TriggerMode::kSoftware:
        arv_camera_set_trigger(camera_, "Software", &error);
        if (error) return failed("TriggerMode On, TriggerSource Software");
        break;
      case TriggerMode::kLine0:
        arv_camera_set_trigger(camera_, "Line0", &error);
        if (error) return failed("TriggerMode On, TriggerSource Line0");
        break;
    }
    return read_back();
  }

  CameraSettings settings() const override { return settings_; }
  FrameFormat format() const override { return format_; }

  std::string start() override {
    if (camera_ == nullptr) return "camera " + name() + ": not opened";
    if (auto refusal = linear_model_refusal(); !refusal.empty()) return refusal;
    if (!mapping_of(arv_format_))
      return "camera " + name() + ": PixelFormat " + pixel_format_string_ +
             " is not one flutterscan reads (Mono8/10/12/16, RGB8, BGR8, BayerRG8/10/12/16)";
    GError* error = nullptr;
    stream_ = arv_camera_create_stream(camera_, nullptr, nullptr, &error);
    if (stream_ == nullptr)
      return "camera " + name() + ": cannot open a stream: " + take_error(error);
    const guint payload = arv_camera_get_payload(camera_, &error);
    if (error) return "camera " + name() + ": PayloadSize: " + take_error(error);
    for (int i = 0; i < kStreamBuffers; ++i)
      arv_stream_push_buffer(stream_, arv_buffer_new(payload, nullptr));
    arv_camera_set_acquisition_mode(camera_, ARV_ACQUISITION_MODE_CONTINUOUS, &error);
    g_clear_error(&error);
    arv_camera_start_acquisition(camera_, &error);
    if (error) return "camera " + name() + ": AcquisitionStart: " + take_error(error);
    counters_ = {};
    last_frame_id_.reset();
    return {};
  }

  FrameWait next_frame(Frame& frame, std::chrono::milliseconds timeout,
                       std::string& error) override {
    if (stream_ == nullptr) {
      error = "camera " + name() + ": not started";
      return FrameWait::kError;
    }
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    for (;;) {
      const auto left = std::chrono::duration_cast<std::chrono::microseconds>(
          deadline - std::chrono::steady_clock::now());
      ArvBuffer* buffer = arv_stream_timeout_pop_buffer(
          stream_, static_cast<guint64>(std::max<long>(0, left.count())));
      if (buffer == nullptr) return FrameWait::kTimeout;
      const guint64 frame_id = arv_buffer_get_frame_id(buffer);
      count_gap(frame_id);
      if (arv_buffer_get_status(buffer) != ARV_BUFFER_STATUS_SUCCESS) {
        ++counters_.incomplete_frames;
        ++counters_.frames_dropped;
        arv_stream_push_buffer(stream_, buffer);
        if (std::chrono::steady_clock::now() >= deadline) return FrameWait::kTimeout;
        continue;
      }
      size_t size = 0;
      const auto* data = static_cast<const std::uint8_t*>(arv_buffer_get_data(buffer, &size));
      const FormatMapping* m = mapping_of(arv_buffer_get_image_pixel_format(buffer));
      if (m == nullptr) {
        arv_stream_push_buffer(stream_, buffer);
        error = "camera " + name() + ": a frame arrived in an unexpected pixel format";
        return FrameWait::kError;
      }
      frame.sequence = frame_id;
      frame.timestamp_ns = static_cast<std::int64_t>(arv_buffer_get_timestamp(buffer));
      frame.host_arrival_ns = host_now_ns();
      frame.format.width = arv_buffer_get_image_width(buffer);
      frame.format.height = arv_buffer_get_image_height(buffer);
      frame.format.pixel_format = m->format;
      frame.format.bit_depth = m->bit_depth;
      frame.format.row_bytes =
          static_cast<std::size_t>(frame.format.width) * bytes_per_pixel(m->format);
      frame.data.assign(data, data + size);
      frame.descriptor_json.clear();
      frame.truth.clear();
      arv_stream_push_buffer(stream_, buffer);
      ++counters_.frames_delivered;
      return FrameWait::kFrame;
    }
  }

  std::string trigger() override {
    if (camera_ == nullptr) return "camera " + name() + ": not opened";
    GError* error = nullptr;
    arv_camera_software_trigger(camera_, &error);
    if (error) return "camera " + name() + ": TriggerSoftware: " + take_error(error);
    return {};
  }

  void stop() override {
    if (stream_ == nullptr) return;
    GError* error = nullptr;
    arv_camera_stop_acquisition(camera_, &error);
    g_clear_error(&error);
    g_object_unref(stream_);
    stream_ = nullptr;
  }

  CameraCounters counters() const override { return counters_; }
  std::vector<std::string> warnings() const override { return warnings_; }

  std::optional<bool> take_software_trigger() {
    if (camera_ == nullptr) return std::nullopt;
    ArvDevice* device = arv_camera_get_device(camera_);
    if (!ARV_IS_FAKE_DEVICE(device)) return std::nullopt;
    return arv_fake_camera_check_and_acknowledge_software_trigger(
               arv_fake_device_get_fake_camera(ARV_FAKE_DEVICE(device))) != FALSE;
  }

  std::string lose_one_frame() {
    if (camera_ == nullptr || stream_ == nullptr) return "camera " + name() + ": not started";
    ArvDevice* device = arv_camera_get_device(camera_);
    if (!ARV_IS_FAKE_DEVICE(device)) return "camera " + name() + ": not Aravis's fake camera";
    ArvFakeCamera* fake = arv_fake_device_get_fake_camera(ARV_FAKE_DEVICE(device));
    GError* error = nullptr;
    ArvBuffer* lost = arv_buffer_new(arv_camera_get_payload(camera_, &error), nullptr);
    g_clear_error(&error);
    guint32 packet_size = 0;
    arv_fake_camera_fill_buffer(fake, lost, &packet_size);
    g_object_unref(lost);
    return {};
  }

 private:
  void count_gap(guint64 frame_id) {
    if (last_frame_id_ && frame_id > *last_frame_id_ + 1)
      counters_.frames_dropped += frame_id - *last_frame_id_ - 1;
    if (!last_frame_id_ || frame_id > *last_frame_id_) last_frame_id_ = frame_id;
  }

  /// The first automatic or curve still on, as a refusal naming it.
  std::string linear_model_refusal() const {
    const std::string prefix = "camera " + name() + ": refusing to start: ";
    if (settings_.auto_exposure) return prefix + "ExposureAuto is still on";
    if (settings_.auto_gain) return prefix + "GainAuto is still on";
    if (settings_.auto_white_balance) return prefix + "BalanceWhiteAuto is still on";
    if (settings_.gamma_or_tone_curve) return prefix + "gamma or the LUT is still on";
    return {};
  }

  std::string read_back() {
    GError* error = nullptr;
    warnings_.clear();
    arv_format_ = arv_camera_get_pixel_format(camera_, &error);
    if (error) return "camera " + name() + ": cannot read PixelFormat: " + take_error(error);
    const char* format_string = arv_camera_get_pixel_format_as_string(camera_, &error);
    g_clear_error(&error);
    pixel_format_string_ = format_string != nullptr ? format_string : "?";
    gint x = 0, y = 0, w = 0, h = 0;
    arv_camera_get_region(camera_, &x, &y, &w, &h, &error);
    if (error) return "camera " + name() + ": cannot read the region: " + take_error(error);
    format_.width = w;
    format_.height = h;
    if (const FormatMapping* m = mapping_of(arv_format_)) {
      format_.pixel_format = m->format;
      format_.bit_depth = m->bit_depth;
      format_.row_bytes = static_cast<std::size_t>(w) * bytes_per_pixel(m->format);
      settings_.pixel_format = m->format;
    } else {
      settings_.pixel_format.reset();
    }
    settings_.width = w;
    settings_.height = h;
    settings_.exposure_us = arv_camera_get_exposure_time(camera_, &error);
    if (error) {
      settings_.exposure_us.reset();
      warnings_.push_back("camera " + name() +
                          ": ExposureTime cannot be read back: " + take_error(error));
    }
    settings_.gain_db = arv_camera_get_gain(camera_, &error);
    if (error) {
      settings_.gain_db.reset();
      g_clear_error(&error);
    }
    settings_.frame_rate_hz = arv_camera_get_frame_rate(camera_, &error);
    if (error) {
      settings_.frame_rate_hz.reset();
      g_clear_error(&error);
    }
    if (has_feature(camera_, "TriggerMode")) {
      const char* mode = arv_camera_get_string(camera_, "TriggerMode", &error);
      g_clear_error(&error);
      const char* source = arv_camera_get_string(camera_, "TriggerSource", &error);
      g_clear_error(&error);
      const std::string mode_text = mode != nullptr ? mode : "";
      const std::string source_text = source != nullptr ? source : "";
      if (mode_text == "Off")
        settings_.trigger = TriggerMode::kFreeRun;
      else if (source_text == "Software")
        settings_.trigger = TriggerMode::kSoftware;
      else if (source_text == "Line0")
        settings_.trigger = TriggerMode::kLine0;
      else
        warnings_.push_back("camera " + name() + ": TriggerMode " + mode_text +
                            " with TriggerSource " + source_text + " is none flutterscan drives");
    }
    settings_.auto_exposure = false;
    if (arv_camera_is_exposure_auto_available(camera_, &error))
      settings_.auto_exposure = arv_camera_get_exposure_time_auto(camera_, &error) != ARV_AUTO_OFF;
    g_clear_error(&error);
    settings_.auto_gain = false;
    if (arv_camera_is_gain_auto_available(camera_, &error))
      settings_.auto_gain = arv_camera_get_gain_auto(camera_, &error) != ARV_AUTO_OFF;
    g_clear_error(&error);
    settings_.auto_white_balance = false;
    if (has_feature(camera_, "BalanceWhiteAuto")) {
      const char* value = arv_camera_get_string(camera_, "BalanceWhiteAuto", &error);
      settings_.auto_white_balance = value == nullptr || std::strcmp(value, "Off") != 0;
      g_clear_error(&error);
    }
    settings_.gamma_or_tone_curve = false;
    if (has_feature(camera_, "GammaEnable")) {
      settings_.gamma_or_tone_curve |= arv_camera_get_boolean(camera_, "GammaEnable", &error);
      g_clear_error(&error);
    } else if (has_feature(camera_, "Gamma")) {
      const double gamma = arv_camera_get_float(camera_, "Gamma", &error);
      settings_.gamma_or_tone_curve |= gamma < 0.999 || gamma > 1.001;
      g_clear_error(&error);
    }
    if (has_feature(camera_, "LUTEnable")) {
      settings_.gamma_or_tone_curve |= arv_camera_get_boolean(camera_, "LUTEnable", &error);
      g_clear_error(&error);
    }
    if (!has_feature(camera_, "BalanceWhiteAuto") && !has_feature(camera_, "Gamma") &&
        !has_feature(camera_, "GammaEnable") && !has_feature(camera_, "LUTEnable"))
      warnings_.push_back("camera " + name() +
                          ": exposes no BalanceWhiteAuto, Gamma, GammaEnable or LUTEnable; "
                          "assumed linear without white balance (check the camera's manual)");
    return {};
  }

  std::string device_id_;
  ArvCamera* camera_ = nullptr;
  ArvStream* stream_ = nullptr;
  ArvPixelFormat arv_format_ = 0;
  std::string pixel_format_string_;
  FrameFormat format_;
  CameraSettings settings_;
  CameraCounters counters_;
  std::optional<guint64> last_frame_id_;
  std::vector<std::string> warnings_;
};

std::vector<CameraInfo> list_aravis_cameras() {
  std::vector<CameraInfo> cameras;
  arv_update_device_list();
  const unsigned n = arv_get_n_devices();
  for (unsigned i = 0; i < n; ++i) {
    const char* id = arv_get_device_id(i);
    if (id == nullptr) continue;
    CameraInfo info;
    info.spec = std::string("aravis:") + id;
    const char* vendor = arv_get_device_vendor(i);
    const char* model = arv_get_device_model(i);
    const char* protocol = arv_get_device_protocol(i);
    info.description = std::string(vendor ? vendor : "?") + " " + (model ? model : "?") + " (" +
                       (protocol ? protocol : "?") + ")";
    GError* error = nullptr;
    if (ArvCamera* camera = arv_camera_new(id, &error)) {
      guint count = 0;
      const char** formats =
          arv_camera_dup_available_pixel_formats_as_strings(camera, &count, &error);
      for (guint k = 0; formats != nullptr && k < count; ++k)
        info.pixel_formats.push_back(formats[k]);
      g_free(formats);
      g_clear_error(&error);
      guint sources = 0;
      const char** triggers = arv_camera_dup_available_trigger_sources(camera, &sources, &error);
      for (guint k = 0; triggers != nullptr && k < sources; ++k)
        info.features.push_back(std::string("trigger ") + triggers[k]);
      g_free(triggers);
      g_clear_error(&error);
      if (arv_camera_is_exposure_time_available(camera, &error))
        info.features.push_back("exposure");
      g_clear_error(&error);
      if (arv_camera_is_gain_available(camera, &error)) info.features.push_back("gain");
      g_clear_error(&error);
      g_object_unref(camera);
    } else {
      info.description += " (cannot open: " + take_error(error) + ")";
    }
    cameras.push_back(std::move(info));
  }
  return cameras;
}

}  // namespace

std::unique_ptr<CameraSource> make_aravis_camera(const std::string& device_id) {
  return std::make_unique<AravisCamera>(device_id);
}

std::string lose_one_fake_frame(CameraSource& camera) {
  auto* aravis = dynamic_cast<AravisCamera*>(&camera);
  if (aravis == nullptr) return "camera " + camera.name() + ": not an Aravis camera";
  return aravis->lose_one_frame();
}

std::optional<bool> take_fake_software_trigger(CameraSource& camera) {
  auto* aravis = dynamic_cast<AravisCamera*>(&camera);
  if (aravis == nullptr) return std::nullopt;
  return aravis->take_software_trigger();
}

CameraBackend aravis_camera_backend() {
  CameraBackend backend;
  backend.scheme = "aravis";
  backend.summary = "aravis:ID GenICam cameras (GigE Vision, USB3 Vision) through Aravis 0.8";
  backend.create = [](const std::string& argument, const CameraContext&, std::string& error) {
    if (argument.empty()) {
      error =
          "camera 'aravis': give the device id, e.g. aravis:Basler-acA1920-12345 "
          "(flutterscan cameras lists them)";
      return std::unique_ptr<CameraSource>();
    }
    return make_aravis_camera(argument);
  };
  backend.list = list_aravis_cameras;
  return backend;
}

}  // namespace flutterscan::capture
