#pragma once
// One interface for every camera the session can read frames from, and a
// list of backends by name: "v4l2:/dev/video0", "aravis:NAME",
// "files:DIR", "sim", "libcamera:ID".
//
// Life cycle: open() -> configure() (settings read back from the device) ->
// start() -> next_frame() ... -> stop(). Every call that can fail returns an
// error text naming the setting or the device (empty = success), in the
// style of imaging::capture_model_problem.
//
// The linear model (docs/conventions.md, "The forward model") needs pixel values proportional to
// light: every backend turns off auto exposure, auto gain, auto white balance
// and gamma/tone curves. A backend that cannot turn one off refuses to start
// naming the setting; a backend that cannot even read it back adds a warning
// (CameraSource::warnings) naming it.

#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace flutterscan::device {
class VirtualController;
}

namespace flutterscan::capture {

/// \brief How pixels are laid out in Frame::data.
enum class PixelFormat {
  kMono8,        ///< one byte per pixel
  kMono16,       ///< little-endian 16-bit container, bit_depth significant low bits
  kRgb8,         ///< R, G, B bytes
  kBgr8,         ///< B, G, R bytes
  kRgb16,        ///< R, G, B little-endian 16-bit containers
  kBayerRggb8,   ///< raw RGGB mosaic, one byte per site
  kBayerRggb16,  ///< raw RGGB mosaic, 16-bit containers, bit_depth significant low bits
  kYuyv,         ///< 4:2:2 packed: mixes the channels (accepted with a warning)
  kMjpeg,        ///< compressed: mixes the channels (accepted with a warning)
};

/// \brief "mono8", "mono16", "rgb8", "bgr8", "rgb16", "bayer-rggb8", "bayer-rggb16", "yuyv",
/// "mjpeg".
std::string pixel_format_name(PixelFormat format);
/// \brief The format called `name` (see pixel_format_name), if any.
std::optional<PixelFormat> pixel_format_from_name(const std::string& name);
/// \brief True for formats whose values keep the camera channels apart (every
/// one but YUYV and MJPEG).
bool keeps_channels_apart(PixelFormat format);
/// \brief True for the raw Bayer mosaics (kBayerRggb8, kBayerRggb16).
bool is_bayer_mosaic(PixelFormat format);
/// \brief Bytes per pixel of an uncompressed format (YUYV: 2; MJPEG: 0).
int bytes_per_pixel(PixelFormat format);

/// \brief Size and layout of a frame.
struct FrameFormat {
  int width = 0;
  int height = 0;
  PixelFormat pixel_format = PixelFormat::kRgb8;
  int bit_depth = 8;          ///< significant bits per sample
  std::size_t row_bytes = 0;  ///< stride of Frame::data (0 = width * bytes_per_pixel)
};

/// \brief A label's symbol as the simulator placed it in a frame: what a read of
/// it should report (the read record's ground truth).
struct TruthLabel {
  std::string value;
  std::string symbology_id;  ///< ISO/IEC 15424, e.g. "]C0"
  /// Top-left, top-right, bottom-right, bottom-left of the symbol where it was
  /// at the exposure's first slot (the deblurred latent's geometry), frame
  /// pixels, pixel-centre coordinates.
  std::array<std::array<double, 2>, 4> corners{};
  double module_px = 0;
};

/// \brief One captured frame, owned (backends copy out of their DMA buffers).
struct Frame {
  std::uint64_t sequence = 0;     ///< the camera's frame counter (V4L2 sequence, GenICam frame id)
  std::int64_t timestamp_ns = 0;  ///< the camera's clock, start of exposure where known
  FrameFormat format;
  std::vector<std::uint8_t> data;
  /// Host monotonic time (steady_clock, ns) at which the frame reached the host.
  std::int64_t host_arrival_ns = 0;
  /// The capture descriptor (docs/formats.md) travelling with the frame, when
  /// the backend has one (files, sim); empty otherwise.
  std::string descriptor_json;
  /// Ground-truth values of the labels a deblur can recover whole (sim only; for
  /// tests and reports): each should be read.
  std::vector<std::string> truth;
  /// Ground-truth values of every label at least partly in view (sim only): a
  /// value read that is none of these is wrong.
  std::vector<std::string> truth_in_view;
  /// Where the labels of `truth` lie (sim only).
  std::vector<TruthLabel> truth_labels;
};

/// \brief Where exposures start.
enum class TriggerMode {
  kFreeRun,   ///< the camera's own frame clock
  kSoftware,  ///< trigger() starts each exposure
  kLine0,     ///< hardware input line 0: the LED controller in master mode
};

/// \brief "free-run", "software", "line0".
std::string trigger_mode_name(TriggerMode mode);
/// \brief The mode called `name` (see trigger_mode_name), if any.
std::optional<TriggerMode> trigger_mode_from_name(const std::string& name);

/// \brief What the session asks of a camera; unset members keep the camera's
/// current value. configure() returns what the device actually took.
struct CameraSettings {
  std::optional<int> width;
  std::optional<int> height;
  std::optional<PixelFormat> pixel_format;
  std::optional<double> exposure_us;
  std::optional<double> gain_db;
  std::optional<double> frame_rate_hz;
  TriggerMode trigger = TriggerMode::kFreeRun;
  /// The automatics and curves that break the linear model: configure() asks
  /// for all of them off and reads them back (true = still on).
  bool auto_exposure = false;
  bool auto_gain = false;
  bool auto_white_balance = false;
  bool gamma_or_tone_curve = false;
};

/// \brief Counters a backend keeps from start().
struct CameraCounters {
  std::uint64_t frames_delivered = 0;
  /// Frames the camera numbered but the host never got (gaps in Frame::sequence),
  /// plus frames the backend discarded itself (incomplete buffers).
  std::uint64_t frames_dropped = 0;
  std::uint64_t incomplete_frames = 0;  ///< part of frames_dropped: buffers that arrived broken
  /// Host time spent making the frames delivered, ms: the sim's rendering (on its
  /// render threads); 0 for a camera, whose frames the host only receives.
  double making_ms = 0;
};

/// \brief What the frame waiter got.
enum class FrameWait { kFrame, kTimeout, kEnd, kError };

/// \brief A camera: one per device, used from one thread at a time.
class CameraSource {
 public:
  virtual ~CameraSource() = default;

  /// \brief The spec it was opened with, e.g. "v4l2:/dev/video0".
  virtual std::string name() const = 0;
  /// \brief Opens the device; error names the device and the cause.
  virtual std::string open() = 0;
  /// \brief Applies `wanted`, turns off every automatic of CameraSettings,
  /// reads everything back into settings(). Error names the setting refused.
  virtual std::string configure(const CameraSettings& wanted) = 0;
  /// \brief The settings as read back from the device after configure().
  virtual CameraSettings settings() const = 0;
  /// \brief The frame format frames will have after start().
  virtual FrameFormat format() const = 0;
  /// \brief Starts streaming. Refuses (error naming the setting) if an
  /// automatic or curve that breaks the linear model is still on.
  virtual std::string start() = 0;
  /// \brief Waits up to `timeout` for the next frame. kEnd: the source has no
  /// more frames (files, sim with a frame limit); kError: `error` says why.
  virtual FrameWait next_frame(Frame& frame, std::chrono::milliseconds timeout,
                               std::string& error) = 0;
  /// \brief Software trigger (TriggerMode::kSoftware); error if not supported.
  virtual std::string trigger() { return name() + ": software trigger not supported"; }
  /// \brief Stops streaming; safe to call twice.
  virtual void stop() = 0;
  /// \brief Counters since start().
  virtual CameraCounters counters() const = 0;
  /// \brief Whether frames arrive as they are exposed (a camera, a paced sim):
  /// their arrival times are the line's. A source that delivers frames as fast
  /// as it makes or reads them (files, an unpaced sim) is not live.
  virtual bool live() const { return true; }
  /// \brief Settings the backend could neither control nor read back, and
  /// formats accepted with lost accuracy, each a sentence naming it.
  virtual std::vector<std::string> warnings() const { return {}; }
};

/// \brief One attached camera as a backend sees it, for `flutterscan cameras`.
struct CameraInfo {
  std::string spec;                        ///< what to pass to open_camera, e.g. "aravis:Fake_1"
  std::string description;                 ///< vendor, model, serial where known
  std::vector<std::string> pixel_formats;  ///< pixel_format_name of each format offered
  std::vector<std::string> features;       ///< e.g. "trigger line0", "exposure", "gain"
};

/// \brief What some backends need besides their argument.
struct CameraContext {
  /// The virtual controller whose LED transitions light the sim camera and
  /// which the sim conveyor feeds encoder counts; required by "sim".
  device::VirtualController* controller = nullptr;
  /// Backend options as key=value text (e.g. sim "speed_px_per_s=2000").
  std::vector<std::pair<std::string, std::string>> options;
};

/// \brief A backend: makes a camera from the text after "scheme:" and lists attached ones.
struct CameraBackend {
  std::string scheme;  ///< "v4l2", "aravis", "files", "sim", "libcamera"
  std::string summary;
  std::function<std::unique_ptr<CameraSource>(const std::string& argument,
                                              const CameraContext& context, std::string& error)>
      create;
  std::function<std::vector<CameraInfo>()> list;
};

/// \brief Every backend compiled in (backends.hpp): v4l2, aravis, libcamera, files, sim.
std::vector<CameraBackend> camera_backends();
/// \brief Makes the camera named by `spec` ("scheme" or "scheme:argument");
/// null with `error` naming the spec if the scheme is unknown or the backend refuses.
std::unique_ptr<CameraSource> make_camera(const std::string& spec, const CameraContext& context,
                                          std::string& error);

}  // namespace flutterscan::capture
