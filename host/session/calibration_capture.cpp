#include "session/calibration_capture.hpp"

#include <algorithm>
#include <bit>
#include <cmath>

#include "capture/frame_pixels.hpp"
#include "device/controller_client.hpp"
#include "imaging/bayer.hpp"
#include "session/line_devices.hpp"

namespace flutterscan::session {

struct CalibrationRig::Parts {
  ControllerLink link;
  std::unique_ptr<capture::CameraSource> camera;
};

namespace {

CaptureFailure line_failure(std::string message) {
  return CaptureFailure{std::move(message), false};
}

}  // namespace

CalibrationRig::CalibrationRig(RigOptions options)
    : options_(std::move(options)), parts_(std::make_unique<Parts>()) {}

CalibrationRig::~CalibrationRig() {
  if (parts_->camera) parts_->camera->stop();
  if (parts_->link.client) {
    (void)parts_->link.client->disarm();
    (void)parts_->link.client->select_code(0);
  }
}

Captured<std::unique_ptr<CalibrationRig>> CalibrationRig::open(RigOptions options) {
  using Out = Captured<std::unique_ptr<CalibrationRig>>;
  if (auto problem = check_config(options.config); !problem.empty())
    return Out::failure({"config: " + problem, true});
  std::unique_ptr<CalibrationRig> rig(new CalibrationRig(std::move(options)));
  SessionHooks hooks;
  hooks.virtual_controller = rig->options_.virtual_controller;
  bool bad_input = false;
  const SessionConfig& config = rig->options_.config;
  if (auto problem = connect_controller(config, hooks, rig->parts_->link, bad_input);
      !problem.empty())
    return Out::failure({problem, bad_input});
  rig->say("controller: " + rig->parts_->link.description +
           " set up as for a session (disarmed, the session's code as code 0)");
  std::string error;
  rig->parts_->camera =
      open_camera(config.camera, rig->parts_->link.virtual_controller.get(), error, bad_input);
  if (!rig->parts_->camera) return Out::failure({error, bad_input});
  for (const auto& warning : rig->parts_->camera->warnings()) rig->say("warning: " + warning);
  const capture::PixelFormat format = rig->parts_->camera->format().pixel_format;
  if (!capture::keeps_channels_apart(format))
    return Out::failure({"camera " + config.camera.spec + ": pixel format " +
                             capture::pixel_format_name(format) +
                             " mixes the camera channels, so the calibration would measure the "
                             "conversion: use raw Bayer or RGB",
                         true});
  return Out::success(std::move(rig));
}

std::string CalibrationRig::where() const {
  return "camera " + options_.config.camera.spec + " with " + parts_->link.description;
}

double CalibrationRig::full_scale_dn() const {
  return std::pow(2.0, parts_->camera->format().bit_depth) - 1;
}

capture::FrameFormat CalibrationRig::format() const {
  return parts_->camera->format();
}

void CalibrationRig::say(const std::string& text) const {
  if (options_.progress) options_.progress(text);
}

std::string CalibrationRig::prepare(const LedCode* pattern, std::uint8_t code_id) {
  device::ControllerClient& client = *parts_->link.client;
  if (auto r = client.disarm(); !r.ok()) return "Disarm: " + r.error().message;
  while (client.next_event(std::chrono::milliseconds(0))) {
  }
  if (pattern == nullptr) return {};
  if (code_id != 0) {
    bool one_of_n = true;
    for (int t = 0; t < pattern->length(); ++t)
      one_of_n = one_of_n && std::popcount(pattern->mask(t)) == 1;
    if (auto r = client.set_code(code_id, *pattern, one_of_n); !r.ok())
      return "SetCode " + std::to_string(code_id) + ": " + r.error().message;
  }
  if (auto r = client.select_code(code_id); !r.ok())
    return "SelectCode " + std::to_string(code_id) + ": " + r.error().message;
  if (auto r = client.arm(); !r.ok()) return "Arm: " + r.error().message;
  return {};
}

std::vector<ExposureRecord> CalibrationRig::finish() {
  device::ControllerClient& client = *parts_->link.client;
  std::vector<ExposureRecord> events;
  (void)client.disarm();
  // Events still on their way: until none arrives for 100 ms.
  while (auto notice = client.next_event(std::chrono::milliseconds(100)))
    events.push_back(exposure_record(*notice));
  return events;
}

Captured<std::vector<capture::Frame>> CalibrationRig::take(int count, const std::string& what) {
  using Out = Captured<std::vector<capture::Frame>>;
  capture::CameraSource& camera = *parts_->camera;
  if (auto problem = camera.start(); !problem.empty())
    return Out::failure(line_failure(where() + ": " + problem));
  std::vector<capture::Frame> frames;
  int skipped = 0;
  while (static_cast<int>(frames.size()) < count) {
    capture::Frame frame;
    std::string error;
    const auto got = camera.next_frame(frame, options_.frame_timeout, error);
    std::string problem;
    if (got == capture::FrameWait::kTimeout)
      problem = "no frame within " + std::to_string(options_.frame_timeout.count()) + " ms";
    else if (got == capture::FrameWait::kEnd)
      problem = "the camera ended after " + std::to_string(frames.size() + skipped) + " frames";
    else if (got == capture::FrameWait::kError)
      problem = error;
    if (!problem.empty()) {
      camera.stop();
      return Out::failure(line_failure(where() + ", " + what + ": " + problem));
    }
    if (skipped < options_.settle_frames) {
      ++skipped;
      continue;
    }
    frames.push_back(std::move(frame));
  }
  camera.stop();
  return Out::success(std::move(frames));
}

Captured<std::vector<imaging::Image>> CalibrationRig::dark(int count) {
  using Out = Captured<std::vector<imaging::Image>>;
  // In master mode the controller triggers the camera: it stays armed, with a
  // pattern that lights nothing. Otherwise it is disarmed.
  const bool master = options_.config.controller.sync == "master";
  const LedCode none = LedCode::from_masks(std::vector<std::uint8_t>(52, 0), 3).value();
  if (auto problem = prepare(master ? &none : nullptr, kCalibrationCodeId); !problem.empty()) {
    finish();
    return Out::failure(line_failure(parts_->link.description + ", dark frames: " + problem));
  }
  say("dark: " + std::to_string(count) + " frames with every LED off (" +
      (master ? "code " + std::to_string(kCalibrationCodeId) + " lights no slot)"
              : "the controller disarmed)"));
  auto frames = take(count, "dark frames");
  finish();
  if (!frames.ok()) return Out::failure(frames.error());
  std::vector<imaging::Image> planes;
  for (const auto& frame : frames.value()) {
    auto p = calibration_planes(frame);
    if (!p.ok()) return Out::failure(line_failure(where() + ", dark frames: " + p.error()));
    planes.push_back(std::move(p.value()));
  }
  return Out::success(std::move(planes));
}

Captured<std::vector<imaging::Image>> CalibrationRig::lit(const LedCode& pattern, int count,
                                                          const std::string& what) {
  using Out = Captured<std::vector<imaging::Image>>;
  if (auto problem = prepare(&pattern, kCalibrationCodeId); !problem.empty()) {
    finish();
    return Out::failure(line_failure(parts_->link.description + ", " + what + ": " + problem));
  }
  say(what + ": " + std::to_string(count) + " frames lit by code " +
      std::to_string(kCalibrationCodeId) + " (" + std::to_string(pattern.length()) + " slots)");
  auto frames = take(count, what);
  const std::vector<ExposureRecord> events = finish();
  if (!frames.ok()) return Out::failure(frames.error());
  int lit_events = 0;
  for (const auto& e : events) {
    if (e.flags & protocol::kEventGuardHit)
      return Out::failure(line_failure(
          parts_->link.description + ", " + what +
          ": the thermal guard kept the LEDs off (raise its limits with flutterscan device "
          "set-guard, or shorten the slot time)"));
    if (e.code_id == kCalibrationCodeId) ++lit_events;
  }
  if (lit_events == 0)
    return Out::failure(
        line_failure(where() + ", " + what + ": the controller reported no exposure while armed (" +
                     (options_.config.controller.sync == "master"
                          ? "is its trigger output wired to the camera's trigger input?"
                          : "is the camera's strobe output wired to the controller?") +
                     ")"));
  std::vector<imaging::Image> planes;
  for (const auto& frame : frames.value()) {
    auto p = calibration_planes(frame);
    if (!p.ok()) return Out::failure(line_failure(where() + ", " + what + ": " + p.error()));
    planes.push_back(std::move(p.value()));
  }
  return Out::success(std::move(planes));
}

Captured<std::vector<CodedFrame>> CalibrationRig::coded(int count) {
  using Out = Captured<std::vector<CodedFrame>>;
  const LedCode& code = options_.config.controller.parsed_code;
  const std::string what =
      "frames under the session's code '" + options_.config.controller.code + "'";
  if (auto problem = prepare(&code, 0); !problem.empty()) {
    finish();
    return Out::failure(line_failure(parts_->link.description + ", " + what + ": " + problem));
  }
  say("speed: " + std::to_string(count) + " " + what + " (code 0), with their exposure events");
  auto frames = take(count, what);
  const std::vector<ExposureRecord> events = finish();
  if (!frames.ok()) return Out::failure(frames.error());
  MatcherOptions matcher_options;
  matcher_options.tolerance_us = options_.config.processing.match_tolerance_us;
  FrameMatcher matcher(matcher_options);
  for (const auto& e : events)
    if (e.code_id == 0) matcher.add_event(e);
  std::vector<FrameMatch> matches;
  for (const auto& frame : frames.value()) {
    FrameStamp stamp;
    stamp.sequence = frame.sequence;
    stamp.timestamp_ns = frame.timestamp_ns;
    for (auto& m : matcher.add_frame(stamp)) matches.push_back(std::move(m));
  }
  for (auto& m : matcher.flush()) matches.push_back(std::move(m));
  std::vector<CodedFrame> out;
  for (const auto& m : matches) {
    if (!m.event) {
      say("frame " + std::to_string(m.frame.sequence) + " left out: " + m.why);
      continue;
    }
    const auto frame = std::find_if(frames.value().begin(), frames.value().end(),
                                    [&](const auto& f) { return f.sequence == m.frame.sequence; });
    auto dn = capture::frame_to_dn(*frame);
    if (!dn.ok()) return Out::failure(line_failure(where() + ", " + what + ": " + dn.error()));
    out.push_back({std::move(dn.value()), frame->format, *m.event, frame->sequence});
  }
  if (out.empty())
    return Out::failure(line_failure(where() + ", " + what + ": no frame matched an exposure " +
                                     "event (" + std::to_string(events.size()) + " events for " +
                                     std::to_string(frames.value().size()) + " frames)"));
  return Out::success(std::move(out));
}

Result<imaging::Image, std::string> calibration_planes(const capture::Frame& frame) {
  auto dn = capture::frame_to_dn(frame);
  if (!dn.ok()) return dn;
  const auto format = frame.format.pixel_format;
  if (format != capture::PixelFormat::kBayerRggb8 && format != capture::PixelFormat::kBayerRggb16)
    return dn;
  imaging::Image planes = imaging::split_bayer_planes(dn.value().channels[0]);
  planes.channels.erase(planes.channels.begin() + 2);  // R, G1, B
  return Result<imaging::Image, std::string>::success(std::move(planes));
}

imaging::Image mean_of(const std::vector<imaging::Image>& frames) {
  imaging::Image mean;
  if (frames.empty()) return mean;
  const auto n = static_cast<float>(frames.size());
  for (std::size_t c = 0; c < frames.front().channels.size(); ++c) {
    const imaging::Plane& first = frames.front().channels[c];
    imaging::Plane sum(first.width, first.height, 0.0f);
    for (const auto& frame : frames)
      for (int y = 0; y < sum.height; ++y)
        for (int x = 0; x < sum.width; ++x) sum.at(x, y) += frame.channels[c].at(x, y);
    for (int y = 0; y < sum.height; ++y)
      for (int x = 0; x < sum.width; ++x) sum.at(x, y) /= n;
    mean.channels.push_back(std::move(sum));
  }
  return mean;
}

LedCode single_led_pattern(int led, int slots) {
  const std::vector<std::uint8_t> masks(static_cast<std::size_t>(slots),
                                        static_cast<std::uint8_t>(1u << led));
  return LedCode::from_masks(masks, 3).value();
}

LedCode level_pattern(int lit, int slots) {
  std::vector<std::uint8_t> masks(static_cast<std::size_t>(slots), 0);
  for (int i = 0; i < lit; ++i) {
    const auto slot = std::lround(static_cast<double>(i) * (slots - 1) / (lit - 1));
    masks[static_cast<std::size_t>(slot)] = 7;
  }
  return LedCode::from_masks(masks, 3).value();
}

}  // namespace flutterscan::session
