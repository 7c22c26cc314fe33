#include "app/calibrate_live.hpp"

#include <algorithm>
#include <filesystem>
#include <iostream>
#include <memory>

#include "app/cli_errors.hpp"

namespace flutterscan::app {
namespace {

[[noreturn]] void fail(const session::CaptureFailure& failure) {
  if (failure.bad_input) throw UsageError(failure.message);
  throw RuntimeFailure(failure.message);
}

void say(const std::string& text) {
  std::cerr << "flutterscan calibrate: " << text << "\n";
}

template <typename T>
T take_or_fail(session::Captured<T> captured) {
  if (!captured.ok()) fail(captured.error());
  return std::move(captured.value());
}

/// The session config (--config when the file exists) with the command line's
/// camera and controller. For a calibration on a white target (`static_target`)
/// the sim camera shows its white card unless another target was asked for.
session::SessionConfig live_config(const LiveFlags& live, bool static_target) {
  session::SessionConfig config;
  if (!live.config.empty() && std::filesystem::exists(live.config)) {
    auto loaded = session::load_config(live.config);
    if (!loaded.ok()) throw UsageError("--config: " + loaded.error());
    config = loaded.value();
  }
  config.camera.spec = live.camera;
  if (!live.controller.empty()) config.controller.spec = live.controller;
  for (const auto& option : live.camera_options) {
    const auto equals = option.find('=');
    if (equals == std::string::npos || equals == 0)
      throw UsageError("--camera-option '" + option + "' must be KEY=VALUE");
    config.camera.options.emplace_back(option.substr(0, equals), option.substr(equals + 1));
  }
  const bool sim = config.camera.spec == "sim" || config.camera.spec.rfind("sim:", 0) == 0;
  const bool target_given =
      std::any_of(config.camera.options.begin(), config.camera.options.end(),
                  [](const auto& option) { return option.first == "target"; });
  if (static_target && sim && !target_given) {
    config.camera.options.emplace_back("target", "white");
    say("camera sim: target=white (a white card, belt stopped)");
  }
  return config;
}

std::unique_ptr<session::CalibrationRig> open_rig(const LiveFlags& live, bool static_target) {
  session::RigOptions options;
  options.config = live_config(live, static_target);
  options.progress = say;
  return take_or_fail(session::CalibrationRig::open(std::move(options)));
}

}  // namespace

void add_live_options(CLI::App* command, LiveFlags& live, const std::string& frames_help) {
  command->add_option("--camera", live.camera,
                      "capture live from this camera (v4l2:/dev/videoN, aravis:ID, sim, ...; "
                      "flutterscan cameras lists them) instead of reading frames from files");
  command->add_option("--controller", live.controller,
                      "with --camera: the LED controller (auto, a serial number, or sim; default "
                      "the config's controller.spec)");
  command->add_option("--camera-option", live.camera_options,
                      "with --camera: backend option KEY=VALUE (repeatable; e.g. the sim's "
                      "target=white:0.9)");
  if (frames_help.empty()) return;
  command->add_option("--frames", live.frames, frames_help)
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
}

void check_live_or_files(const LiveFlags& live, bool file_inputs, const std::string& file_options) {
  if (!live.camera.empty() && file_inputs)
    throw UsageError("give either " + file_options +
                     " (frames on disk) or --camera (capture live), not both");
  if (live.camera.empty() && (!live.controller.empty() || !live.camera_options.empty()))
    throw UsageError("--controller and --camera-option need --camera (the live form)");
  if (live.camera.empty() && !file_inputs)
    throw UsageError("give " + file_options +
                     " (frames on disk), or --camera and --controller to capture live");
}

WhiteFrames capture_white_frames(const LiveFlags& live) {
  auto rig = open_rig(live, true);
  WhiteFrames out;
  out.full_scale_dn = rig->full_scale_dn();
  out.dark = session::mean_of(take_or_fail(rig->dark(live.frames)));
  static const char* const kNames[] = {"LED 0 (pattern 1111...)", "LED 1 (pattern 2222...)",
                                       "LED 2 (pattern 4444...)"};
  for (int k = 0; k < 3; ++k)
    out.lit.push_back(
        session::mean_of(take_or_fail(rig->lit(session::single_led_pattern(k), live.frames,
                                               kNames[k]))));
  return out;
}

NoiseFrames capture_noise_frames(const LiveFlags& live, const std::vector<int>& lit_slots) {
  for (int n : lit_slots)
    if (n < 2 || n > 52)
      throw UsageError("--lit-slots: " + std::to_string(n) + " is not within 2..52");
  auto rig = open_rig(live, true);
  NoiseFrames out;
  out.full_scale_dn = rig->full_scale_dn();
  auto dark = take_or_fail(rig->dark(2));
  out.dark = {std::move(dark[0]), std::move(dark[1])};
  for (int n : lit_slots) {
    auto pair = take_or_fail(rig->lit(session::level_pattern(n), 2,
                                      "light level " + std::to_string(n) + " of 52 slots"));
    out.flats.push_back({std::move(pair[0]), std::move(pair[1])});
  }
  return out;
}

SpeedFrames capture_speed_frames(const LiveFlags& live) {
  auto rig = open_rig(live, false);
  SpeedFrames out;
  out.frames = take_or_fail(rig->coded(live.frames));
  out.config = rig->config();
  return out;
}

}  // namespace flutterscan::app
