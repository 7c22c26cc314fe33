#pragma once
// The live forms of `flutterscan calibrate` (--camera SPEC [--controller SPEC]):
// the frames each calibration needs, taken with the session's camera and
// controller (host/session/calibration_capture.hpp) instead of read from
// files. The session config given with --config (when it exists) supplies the
// camera settings and options, the controller's timing, sync and code, and the
// optics the speed calibration models frames with. On the sim camera the
// white-target calibrations show its white card (target=white) unless told
// otherwise. Failures throw UsageError
// (exit 2: a spec or setting the user got wrong) or RuntimeFailure (exit 1:
// the line failed), naming the camera, the controller and the step.

#include <CLI/CLI.hpp>

#include <string>
#include <vector>

#include "imaging/image.hpp"
#include "imaging/photon_transfer.hpp"
#include "session/calibration_capture.hpp"

namespace flutterscan::app {

/// \brief What a live calibration is told on the command line.
struct LiveFlags {
  std::string camera;      ///< empty: calibrate from files
  std::string controller;  ///< empty: the config's controller.spec
  std::vector<std::string> camera_options;  ///< KEY=VALUE
  int frames = 4;                           ///< per pattern (crosstalk, flat) or in all (speed)
  std::string config;                       ///< session config to read, if it exists
};

/// \brief Adds --camera, --controller, --camera-option and (unless `frames_help` is
/// empty) --frames.
void add_live_options(CLI::App* command, LiveFlags& live, const std::string& frames_help);

/// \brief Refuses mixing the live form with frames on disk: `file_inputs` says
/// whether any of `file_options` (e.g. "--dark/--led") was given.
void check_live_or_files(const LiveFlags& live, bool file_inputs, const std::string& file_options);

/// \brief White-target frames: the mean of live.frames dark frames and, per LED,
/// of live.frames frames lit by 1111..., 2222..., 4444....
struct WhiteFrames {
  imaging::Image dark;
  std::vector<imaging::Image> lit;
  double full_scale_dn = 0;
};
WhiteFrames capture_white_frames(const LiveFlags& live);

/// \brief Photon transfer frames: a dark pair and a pair per light level, the
/// level set by how many of 52 slots light all three LEDs (level_pattern).
struct NoiseFrames {
  imaging::FlatPair dark;
  std::vector<imaging::FlatPair> flats;
  double full_scale_dn = 0;
};
NoiseFrames capture_noise_frames(const LiveFlags& live, const std::vector<int>& lit_slots);

/// \brief Coded frames of a moving target under the session's code, with their
/// exposure events, and the session config (optics) to model them with.
struct SpeedFrames {
  std::vector<session::CodedFrame> frames;
  session::SessionConfig config;
};
SpeedFrames capture_speed_frames(const LiveFlags& live);

}  // namespace flutterscan::app
