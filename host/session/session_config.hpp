#pragma once
// A session's configuration: TOML (docs/session.md, docs/session-example.toml)
// read with toml++, then command-line overrides. Every field has a default, so
// an empty file (or none) is a valid sim session.

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "capture/camera_source.hpp"
#include "codes/scheme_choice.hpp"
#include "flutterscan/common/led_code.hpp"
#include "flutterscan/common/result.hpp"
#include "imaging/deblur.hpp"
#include "reader/barcode_reader.hpp"
#include "reader/reader_options.hpp"
#include "session/second_pass_tries.hpp"

namespace flutterscan::session {

struct CameraConfig {
  std::string spec = "sim";  ///< backend:argument (camera_source.hpp)
  capture::CameraSettings settings;
  /// Backend options as key = value ([camera.options]; the sim's conveyor).
  std::vector<std::pair<std::string, std::string>> options;
};

struct ControllerConfig {
  std::string spec = "sim";  ///< "sim", "auto" or a serial number
  /// Digits, a library name (docs/codes.md), a white strobe "snapshot-K" (all
  /// LEDs for the first K slots, codes::snapshot_code), or "auto": the scheme the regime
  /// map says wins at the light level the session measures before it starts
  /// (session/light_probe.hpp), optics.read_noise_e and optics.cap.
  std::string code = "seed-maxmin-1";
  LedCode parsed_code;  ///< filled by check_config
  /// Code "auto": check_config's provisional choice at optics.electrons, which
  /// run_session replaces by the choice at the measured light.
  std::optional<codes::SchemeChoice> scheme;
  int probe_frames = 6;  ///< code "auto": frames lit by the light probe
  std::uint32_t slot_time_us = 100;
  std::string sync = "slave";         ///< "slave" (camera strobe) or "master" (controller triggers)
  std::uint32_t frame_period_us = 0;  ///< master mode
};

/// \brief How the camera sees the LEDs (calibration), for the capture descriptor.
struct OpticsConfig {
  double px_per_count = 0.5;  ///< belt motion in image pixels per encoder count
  /// The line has an encoder: the blur is its counts x px_per_count. false: each
  /// frame's blur is estimated from the frame, around nominal_blur_px.
  bool encoder = true;
  double nominal_blur_px = 0;  ///< without an encoder: the blur at the line's nominal speed
  double line_time_us = 0;     ///< rolling-shutter line time (0: global shutter)
  std::string flat_field;      ///< flat-field file (calibrate flat); empty: uniform light
  std::string direction = "+x";
  std::vector<double> crosstalk = {0.90, 0.08, 0.01, 0.10, 0.85, 0.12, 0.01, 0.07, 0.88};
  double electrons = 3000;  ///< E: white e- per channel under rect-white (sets I_k with cap)
  /// optics.electrons was in the config: code "auto" falls back to it when the
  /// light cannot be measured, and the frames' model keeps it.
  bool electrons_given = false;
  /// Reflectance of the labels' paper (white = 1): code "auto" takes the
  /// brightest paper in the probe frames as this.
  double paper_reflectance = 1.0;
  double cap = 3;
  double read_noise_e = 4;
  double full_well_e = 12000;
  double black_level_dn = 64;
  double gain_e_per_dn = 0;  ///< 0: full well at full scale of bit_depth
  int bit_depth = 12;
};

/// processing.latency_ms at most, and its default: no deadline.
inline constexpr double kMaxLatencyMs = 1e6;

struct ProcessingConfig {
  /// The method that deblurs each whole frame ("cascade": joint Wiener).
  imaging::Method method = imaging::Method::kJointWiener;
  /// Method "cascade" (the default): the label windows joint Wiener read nothing
  /// in are deblurred again by tv, alone (second_pass.hpp).
  bool cascade = true;
  /// The cascade's CPU budget for second passes, ms per frame; < 0 ("auto"):
  /// from the frame rate and the workers, leaving 15% of their time spare.
  double second_pass_ms = -1;
  /// The first pass's decode time per frame, ms: windows are read in turn
  /// (those not tried on the belt lately first) while it lasts, and the rest
  /// are left for the frames after (docs/session.md, "The decode budget"); < 0 ("auto"): the
  /// frame's share of the workers' time (period x workers, less 15% spare) less
  /// its conversion and deblur, every window while the frame rate is unknown
  /// (offline); > 0: that many ms; kMaxDecodeMs: every window.
  double decode_ms = -1;
  /// Each frame's result is due this long after the frame arrived, ms: the
  /// decode and the second pass start no window they expect to end later
  /// (docs/session.md, "The frame's deadline"); < 0 ("auto"): workers + 1 frame
  /// periods, none while the frame rate is unknown or frames do not arrive as
  /// exposed; kMaxLatencyMs (the default): none.
  double latency_ms = kMaxLatencyMs;
  /// The cascade's second-pass tries beyond tv on the window (second_pass_tries.hpp).
  SecondPassTries second_pass_tries;
  int workers = 2;              ///< frames deblurred at once
  int threads_per_worker = 1;   ///< row threads inside one deblur
  std::size_t queue_depth = 4;  ///< frames waiting for a worker; beyond it frames are dropped
  std::uint64_t max_frames =
      0;                   ///< stop after this many frames (0: until the camera ends or Ctrl-C)
  double max_seconds = 0;  ///< stop after this long (0: no limit)
  double match_tolerance_us = 2000;
  double object_match_px = 120;  ///< decodes this close on the belt are one object
  /// Test each frame for colour print (per-channel latents when found); issue 7.
  bool choose_model = true;
  /// With an encoder: every N-th frame, estimate the blur from the frame and flag a
  /// disagreement with the encoder (0: never; each check costs about one tv deblur).
  int blur_check_every = 0;
  /// With an encoder: refine each frame's blur within +-this percentage of the
  /// encoder's (imaging/motion_refinement.hpp); 0 = use the encoder's blur exactly.
  double blur_tolerance_pct = 10;
  /// With refinement on: false (default), a frame taken while half the queue
  /// waits skips the refinement and scales the encoder's blur by the latest
  /// refined frame's ratio (flagged "motion-reused"), so the queue drains
  /// instead of dropping frames; true refines every frame whatever the queue.
  bool refine_when_behind = false;
  // The reader's options (reader_options(): reader/reader_options.hpp, whose defaults these are).
  /// ZXing format names read on each fused frame, comma-separated (fewer is faster).
  std::string symbologies = reader::ReaderOptions{}.symbologies;
  /// Also look for 1-D codes turned by 90 degrees; a line whose labels always
  /// pass the same way up can turn it off and decode in about half the time.
  bool try_rotate = reader::ReaderOptions{}.try_rotate;
  /// Look for codes on the label paper only (bright runs along the motion, the
  /// frame's edges included) or on the whole frame; "frame" for codes printed
  /// straight on a substrate no brighter than the belt.
  reader::DecodeArea decode_area = reader::ReaderOptions{}.area;
};

/// \brief The names processing.method takes: every imaging method and "cascade".
inline constexpr const char* kProcessingMethods = "cascade, joint-wiener, wiener-avg, rl, tv";

/// \brief Sets `processing`'s method (and cascade) from `name`; false if
/// `name` is none of kProcessingMethods.
bool set_processing_method(const std::string& name, ProcessingConfig& processing);

/// \brief The method `processing` names: "cascade" or the imaging method's name.
std::string processing_method_name(const ProcessingConfig& processing);

/// \brief The reader's options of `processing`: symbologies, try_rotate and
/// decode_area; a window of paper or print cut by the frame's edge in the
/// linear view only (the line sees its label whole in another frame).
inline reader::ReaderOptions reader_options(const ProcessingConfig& processing) {
  reader::ReaderOptions options;
  options.symbologies = processing.symbologies;
  options.try_rotate = processing.try_rotate;
  options.area = processing.decode_area;
  options.cut_window_views = 1;
  return options;
}

struct OutputConfig {
  std::string dir = "sessions";
  bool timestamped_subfolder = true;  ///< DIR/YYYYmmdd-HHMMSS, else DIR itself
  int keep_first_frames = 10;         ///< raw + fused images of the first N frames
  bool keep_failed_frames = true;     ///< and of every frame with a NO-READ or a read graded D/F
  double disk_budget_mb = 512;        ///< frame files beyond it rotate away, oldest first
  bool report = true;
};

/// \brief Results over MQTT ([results.mqtt], docs/session-output.md, "Results over MQTT").
struct MqttConfig {
  std::string host;  ///< from broker = "mqtt://HOST[:PORT]" or "mqtts://HOST[:PORT]"
  int port = 1883;   ///< 1883 (mqtt), 8883 (mqtts) unless the URL says
  bool tls = false;  ///< mqtts://
  std::string topic = "flutterscan/results";  ///< objects here, the status on TOPIC/status
  int qos = 1;
  std::string client_id;            ///< empty: "flutterscan-" and the host name
  std::size_t queue_limit = 10000;  ///< results not yet acknowledged; beyond it dropped, counted
  std::string username;
  /// Read from password_file (not readable by others) or the variable password_env; never
  /// from the command line, never written anywhere.
  std::string password;
  std::string ca_file, cert_file, key_file;  ///< TLS; no ca_file: the system's CAs
};

struct ResultsConfig {
  int tcp_port = -1;  ///< -1: off; 0: any free port (printed); else that port
  std::string tcp_bind = "127.0.0.1";
  std::string serial;  ///< e.g. /dev/ttyUSB0; empty: off
  int serial_baud = 115200;
  std::optional<MqttConfig> mqtt;  ///< [results.mqtt]; none: off
};

struct SessionConfig {
  CameraConfig camera;
  ControllerConfig controller;
  OpticsConfig optics;
  ProcessingConfig processing;
  OutputConfig output;
  ResultsConfig results;
};

/// The bounds check_config holds sizes to (besides imaging/limits.hpp's).
inline constexpr double kMaxPxPerCount = 1000;      ///< optics.px_per_count
inline constexpr double kMaxElectrons = 1e9;        ///< optics.electrons, full_well_e
inline constexpr std::size_t kMaxQueueDepth = 256;  ///< processing.queue_depth
inline constexpr double kMaxDiskBudgetMb = 1e9;     ///< output.disk_budget_mb (a petabyte)
inline constexpr double kMaxSecondPassMs = 1e6;     ///< processing.second_pass_ms
inline constexpr double kMaxDecodeMs = 1e6;         ///< processing.decode_ms
inline constexpr double kMaxCrosstalk = 100;        ///< each optics.crosstalk entry
/// results.mqtt.queue_limit: below MQTT's 65535 message ids, each waiting result holding one.
inline constexpr std::size_t kMaxMqttQueue = 50000;

/// \brief Reads a TOML file over the defaults; the error names the file, the key and the line.
Result<SessionConfig, std::string> load_config(const std::string& path);
/// \brief Reads TOML text (`origin` names it in errors).
Result<SessionConfig, std::string> parse_config(const std::string& text, const std::string& origin);
/// \brief Checks values and parses the code; the first problem, naming the key (empty if none).
std::string check_config(SessionConfig& config);

}  // namespace flutterscan::session
