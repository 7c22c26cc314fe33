// libcamera_vimc_check: what `flutterscan scan` cannot show of the libcamera backend, checked
// inside the libcamera vimc VM test's QEMU guest (run_libcamera_vimc_vm.sh) through the same
// backend (flutterscan_capture, make_camera). The scan captures frames but processes none (no
// controller event matches a free-running camera's frames), so the pixels are checked here:
//
//   - for rgb8 and bgr8 (libcamera's BGR888 and RGB888): N frames at WIDTHxHEIGHT, sequence
//     numbers one apart, timestamps increasing, every frame the full image, and the channel
//     order right: vimc's sensor shows 75% colour bars (white, yellow, cyan, green, magenta,
//     red, blue, black), so the yellow bar must read red and green high and blue low, the cyan
//     one blue and green high and red low;
//   - refusals through the real pipeline: a size it changes (its widths are multiples of 6) and
//     an exposure asked of a camera without ExposureTime, each with a message naming it.
//
// One line per check, LIBCAMERA-VM-RESULT <name> PASS|FAIL <details>; exit 0 when all passed.
// Usage: libcamera_vimc_check SPEC [WIDTH HEIGHT FRAMES]

#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "capture/camera_source.hpp"

namespace {

using namespace flutterscan::capture;

int failures = 0;

void result(const std::string& name, bool pass, const std::string& details) {
  std::printf("LIBCAMERA-VM-RESULT %s %s %s\n", name.c_str(), pass ? "PASS" : "FAIL",
              details.c_str());
  std::fflush(stdout);
  if (!pass) ++failures;
}

/// Mean R, G, B over the middle rows of the colour bar `bar` (0..7), read per the frame's format.
std::vector<double> bar_mean(const Frame& frame, int bar) {
  const FrameFormat& f = frame.format;
  const bool rgb = f.pixel_format == PixelFormat::kRgb8;
  const std::size_t stride = f.row_bytes ? f.row_bytes : static_cast<std::size_t>(f.width) * 3;
  const int bar_width = f.width / 8;
  const int x0 = bar * bar_width + bar_width / 4, x1 = bar * bar_width + 3 * bar_width / 4;
  double sum[3] = {0, 0, 0};
  long count = 0;
  for (int y = f.height / 3; y < 2 * f.height / 3; y += 4) {
    for (int x = x0; x < x1; ++x) {
      const std::uint8_t* p = frame.data.data() + y * stride + static_cast<std::size_t>(x) * 3;
      sum[0] += rgb ? p[0] : p[2];
      sum[1] += p[1];
      sum[2] += rgb ? p[2] : p[0];
      ++count;
    }
  }
  return {sum[0] / count, sum[1] / count, sum[2] / count};
}

std::string rgb_text(const std::vector<double>& v) {
  char text[64];
  std::snprintf(text, sizeof text, "(%.0f,%.0f,%.0f)", v[0], v[1], v[2]);
  return text;
}

void capture_check(const std::string& spec, PixelFormat format, int width, int height, int frames) {
  const std::string name = pixel_format_name(format);
  std::string error;
  auto camera = make_camera(spec, {}, error);
  if (!camera) return result(name, false, error);
  if (error = camera->open(); !error.empty()) return result(name, false, error);
  CameraSettings wanted;
  wanted.width = width;
  wanted.height = height;
  wanted.pixel_format = format;
  if (error = camera->configure(wanted); !error.empty()) return result(name, false, error);
  const FrameFormat f = camera->format();
  if (f.width != width || f.height != height || f.pixel_format != format)
    return result(name, false,
                  "format read back " + std::to_string(f.width) + "x" + std::to_string(f.height) +
                      " " + pixel_format_name(f.pixel_format));
  if (error = camera->start(); !error.empty()) return result(name, false, error);
  for (const auto& warning : camera->warnings()) std::printf("warning: %s\n", warning.c_str());
  std::vector<Frame> got;
  std::string problem;
  for (int i = 0; i < frames && problem.empty(); ++i) {
    Frame frame;
    const FrameWait wait = camera->next_frame(frame, std::chrono::seconds(10), error);
    if (wait == FrameWait::kTimeout) problem = "no frame within 10 s after " + std::to_string(i);
    if (wait == FrameWait::kError) problem = error;
    if (wait == FrameWait::kEnd) problem = "the camera ended";
    if (!problem.empty()) break;
    if (frame.data.size() < f.row_bytes * static_cast<std::size_t>(height))
      problem = "frame " + std::to_string(frame.sequence) +
                " short: " + std::to_string(frame.data.size()) + " bytes";
    if (!got.empty() && frame.sequence != got.back().sequence + 1)
      problem = "sequence " + std::to_string(got.back().sequence) + " then " +
                std::to_string(frame.sequence);
    if (!got.empty() && frame.timestamp_ns <= got.back().timestamp_ns)
      problem = "timestamp not increasing at sequence " + std::to_string(frame.sequence);
    got.push_back(std::move(frame));
  }
  const CameraCounters counters = camera->counters();
  camera->stop();
  if (!problem.empty()) return result(name, false, problem);
  const double span_ms = (got.back().timestamp_ns - got.front().timestamp_ns) / 1e6;
  const auto yellow = bar_mean(got.back(), 1), cyan = bar_mean(got.back(), 2);
  const std::string details =
      "frames=" + std::to_string(got.size()) + " sequence=" + std::to_string(got.front().sequence) +
      ".." + std::to_string(got.back().sequence) + " span_ms=" + std::to_string(span_ms) +
      " dropped=" + std::to_string(counters.frames_dropped) +
      " row_bytes=" + std::to_string(f.row_bytes) + " yellow_bar=" + rgb_text(yellow) +
      " cyan_bar=" + rgb_text(cyan);
  // Yellow: red and green well above blue; cyan: blue and green well above red.
  const bool yellow_ok = yellow[0] > yellow[2] + 60 && yellow[1] > yellow[2] + 60;
  const bool cyan_ok = cyan[2] > cyan[0] + 60 && cyan[1] > cyan[0] + 60;
  if (!yellow_ok || !cyan_ok) return result(name, false, "channel order wrong: " + details);
  if (counters.frames_dropped != 0) return result(name, false, "frames dropped: " + details);
  result(name, true, details);
}

void refusal_check(const std::string& name, const std::string& spec, const CameraSettings& wanted,
                   const std::string& expected) {
  std::string error;
  auto camera = make_camera(spec, {}, error);
  if (!camera) return result(name, false, error);
  if (error = camera->open(); !error.empty()) return result(name, false, error);
  error = camera->configure(wanted);
  result(name, error.find(expected) != std::string::npos,
         error.empty() ? "accepted, not refused" : "refused: " + error);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2 && argc != 5) {
    std::fprintf(stderr, "usage: %s SPEC [WIDTH HEIGHT FRAMES]\n", argv[0]);
    return 2;
  }
  const std::string spec = argv[1];
  const int width = argc == 5 ? std::atoi(argv[2]) : 720;
  const int height = argc == 5 ? std::atoi(argv[3]) : 480;
  const int frames = argc == 5 ? std::atoi(argv[4]) : 10;
  capture_check(spec, PixelFormat::kRgb8, width, height, frames);
  capture_check(spec, PixelFormat::kBgr8, width, height, frames);

  CameraSettings odd_size;
  odd_size.width = 640;
  odd_size.height = 480;
  refusal_check("refuses-changed-size", spec, odd_size, "size 640x480 asked, the pipeline set");
  CameraSettings exposure;
  exposure.exposure_us = 5000;
  refusal_check("refuses-exposure", spec, exposure, "has no ExposureTime");
  CameraSettings bayer;
  bayer.pixel_format = PixelFormat::kBayerRggb16;
  refusal_check("refuses-absent-format", spec, bayer, "is not offered");
  return failures == 0 ? 0 : 1;
}
