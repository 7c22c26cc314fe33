#pragma once
// Frames for the live calibrations (`flutterscan calibrate ... --camera SPEC
// --controller SPEC`, docs/calibration.md), taken with the session's own
// camera and controller (line_devices.hpp).
//
// What it does to the controller: connects and sets it up as a session would
// (Disarm, the session's code as code 0, SetTiming, SetMode); for each
// calibration pattern it disarms, uploads the pattern as code
// kCalibrationCodeId, selects it and arms; frames with every LED off are taken
// disarmed (in master mode, where the controller triggers the camera, armed
// with a pattern that lights no slot). The camera is started for each pattern (the first settle
// frames dropped, so no frame exposed under the previous pattern counts) and stopped after it.
// Every lit pattern must produce exposure events from the controller (else the strobe or trigger is
// not wired) and none may have hit the thermal guard. It leaves the controller disarmed with code 0
// selected.

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "capture/camera_source.hpp"
#include "flutterscan/common/led_code.hpp"
#include "flutterscan/common/result.hpp"
#include "imaging/image.hpp"
#include "session/frame_matcher.hpp"
#include "session/session_config.hpp"

namespace flutterscan::device {
class VirtualController;
}

namespace flutterscan::session {

/// \brief Code table slot the calibration patterns are uploaded to (the session uses 0).
inline constexpr std::uint8_t kCalibrationCodeId = 7;

/// \brief Why a capture failed; `bad_input` when it is the user's input (exit 2),
/// else the line failed (exit 1).
struct CaptureFailure {
  std::string message;
  bool bad_input = false;
};

template <typename T>
using Captured = Result<T, CaptureFailure>;

/// \brief One frame lit by the session's code and the exposure event matched to it.
struct CodedFrame {
  imaging::Image dn;  ///< as captured, one plane per channel
  capture::FrameFormat format;
  ExposureRecord event;
  std::uint64_t sequence = 0;
};

struct RigOptions {
  /// Camera (spec, options, settings), controller (spec, code, timing, sync) and
  /// optics; checked with check_config.
  SessionConfig config;
  /// The virtual controller for controller spec "sim" (made when null).
  std::shared_ptr<device::VirtualController> virtual_controller;
  int settle_frames = 1;  ///< dropped after each camera start
  std::chrono::milliseconds frame_timeout{3000};
  /// One line per step (what the controller is told), for stderr.
  std::function<void(const std::string&)> progress;
};

/// \brief The camera and the controller, opened and driven for calibration frames.
class CalibrationRig {
 public:
  /// \brief Opens the controller, then the camera, as a session does.
  static Captured<std::unique_ptr<CalibrationRig>> open(RigOptions options);
  /// \brief Disarms the controller and stops the camera.
  ~CalibrationRig();
  CalibrationRig(const CalibrationRig&) = delete;
  CalibrationRig& operator=(const CalibrationRig&) = delete;

  /// \brief "camera SPEC with controller SERIAL": where a failure happened.
  std::string where() const;
  /// \brief 2^bit_depth - 1 of the camera's frames.
  double full_scale_dn() const;
  /// \brief The camera's frame format (size, pixel format, bit depth).
  capture::FrameFormat format() const;
  const SessionConfig& config() const { return options_.config; }

  /// \brief `count` frames with every LED off (disarmed; master mode: an unlit pattern).
  Captured<std::vector<imaging::Image>> dark(int count);
  /// \brief `count` frames lit by `pattern`; `what` names it in messages ("LED 0").
  Captured<std::vector<imaging::Image>> lit(const LedCode& pattern, int count,
                                            const std::string& what);
  /// \brief `count` frames lit by the session's code (code 0), each matched to
  /// its exposure event; frames without one are left out (and said).
  Captured<std::vector<CodedFrame>> coded(int count);

 private:
  struct Parts;
  explicit CalibrationRig(RigOptions options);
  /// Starts the camera, drops the settle frames, takes `count`, stops it.
  Captured<std::vector<capture::Frame>> take(int count, const std::string& what);
  /// Disarm, then (for a pattern) upload and select it, then arm.
  std::string prepare(const LedCode* pattern, std::uint8_t code_id);
  /// Disarms and returns the events of the last armed stretch.
  std::vector<ExposureRecord> finish();
  void say(const std::string& text) const;

  RigOptions options_;
  std::unique_ptr<Parts> parts_;
};

/// \brief The frame's samples as planes: R, G, B (for a Bayer mosaic the R, first
/// G and B sites at half resolution), or one plane for mono.
Result<imaging::Image, std::string> calibration_planes(const capture::Frame& frame);

/// \brief The per-pixel mean of frames of one size.
imaging::Image mean_of(const std::vector<imaging::Image>& frames);

/// \brief LED `led` alone in every one of `slots` slots: 1111..., 2222..., 4444....
LedCode single_led_pattern(int led, int slots = 52);

/// \brief All three LEDs in `lit` of `slots` slots (2 <= lit <= slots), spread
/// evenly with the first and the last slot lit, so that the light is about
/// proportional to `lit` at a fixed LED current and sequence length.
LedCode level_pattern(int lit, int slots = 52);

}  // namespace flutterscan::session
