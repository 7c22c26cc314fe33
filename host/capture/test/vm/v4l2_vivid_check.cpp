// v4l2_vivid_check: the capture check that runs inside the vivid VM test's
// QEMU guest (see run_vivid_vm.sh). Statically linked from the v4l2 backend's
// own sources only (flutterscan_v4l2), so it fits in a busybox initramfs.
//
// For each pixel format and I/O method asked for (default: RGB24 and raw
// Bayer SRGGB10, each with MMAP and USERPTR), it opens the device with that
// format, a frame rate and a gain, captures N frames, and checks: sequence numbers gap-free and
// increasing by one, timestamps strictly increasing on the monotonic clock,
// every frame the full image size and not blank, the gain and frame rate
// read back as set, auto gain off. It prints one line per run,
//   V4L2-VM-RESULT io=mmap format=RGB24 PASS frames=30 ...   or   ... FAIL <why>
// which the host side parses. Exit 0 when every run passed, 1 otherwise,
// 2 on bad usage.

#include <linux/videodev2.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "capture/v4l2_camera.hpp"

namespace {

using flutterscan::capture::V4l2Camera;
using flutterscan::capture::V4l2Clock;
using flutterscan::capture::V4l2Config;
using flutterscan::capture::V4l2IoMethod;
using flutterscan::capture::V4l2TimestampSource;

struct Options {
  std::string device = "/dev/video0";
  V4l2Config request;
  int frames = 30;
  std::vector<V4l2IoMethod> methods{V4l2IoMethod::kMmap, V4l2IoMethod::kUserPtr};
  std::vector<std::uint32_t> formats{V4L2_PIX_FMT_RGB24, V4L2_PIX_FMT_SRGGB10};
};

void usage() {
  std::fprintf(
      stderr,
      "usage: v4l2_vivid_check [--device /dev/video0] [--size 640x480] [--format RGB24,SRGGB10]\n"
      "                        [--fps 15] [--gain 120] [--frames 30] [--io mmap,userptr]\n");
}

bool parse(int argc, char** argv, Options& options) {
  options.request.width = 640;
  options.request.height = 480;
  options.request.frame_rate = 15.0;
  options.request.controls.gain = 120;
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    if (i + 1 >= argc) {
      std::fprintf(stderr, "v4l2_vivid_check: %s needs a value\n", flag.c_str());
      return false;
    }
    const std::string value = argv[++i];
    if (flag == "--device") {
      options.device = value;
    } else if (flag == "--size") {
      if (std::sscanf(value.c_str(), "%dx%d", &options.request.width, &options.request.height) !=
          2) {
        std::fprintf(stderr, "v4l2_vivid_check: --size %s is not WIDTHxHEIGHT\n", value.c_str());
        return false;
      }
    } else if (flag == "--format") {
      options.formats.clear();
      std::size_t start = 0;
      while (start <= value.size()) {
        const std::size_t comma = std::min(value.find(',', start), value.size());
        const std::string name = value.substr(start, comma - start);
        const auto fourcc = flutterscan::capture::fourcc_from_name(name);
        if (!fourcc) {
          std::fprintf(stderr, "v4l2_vivid_check: --format %s is unknown\n", name.c_str());
          return false;
        }
        options.formats.push_back(*fourcc);
        start = comma + 1;
      }
    } else if (flag == "--fps") {
      options.request.frame_rate = std::atof(value.c_str());
    } else if (flag == "--gain") {
      options.request.controls.gain = std::atoi(value.c_str());
    } else if (flag == "--frames") {
      options.frames = std::atoi(value.c_str());
      if (options.frames < 2) {
        std::fprintf(stderr, "v4l2_vivid_check: --frames %s: need at least 2\n", value.c_str());
        return false;
      }
    } else if (flag == "--io") {
      options.methods.clear();
      if (value.find("mmap") != std::string::npos) options.methods.push_back(V4l2IoMethod::kMmap);
      if (value.find("userptr") != std::string::npos) {
        options.methods.push_back(V4l2IoMethod::kUserPtr);
      }
      if (options.methods.empty()) {
        std::fprintf(stderr, "v4l2_vivid_check: --io %s names no method\n", value.c_str());
        return false;
      }
    } else {
      std::fprintf(stderr, "v4l2_vivid_check: unknown option %s\n", flag.c_str());
      return false;
    }
  }
  return true;
}

/// Captures and checks with one pixel format and I/O method; prints its result line.
bool check(const Options& options, std::uint32_t fourcc, V4l2IoMethod method) {
  const char* io = flutterscan::capture::v4l2_io_method_name(method);
  const std::string format_name = flutterscan::capture::fourcc_text(fourcc);
  auto fail = [&](const std::string& why) {
    std::printf("V4L2-VM-RESULT io=%s format=%s FAIL %s\n", io, format_name.c_str(), why.c_str());
    std::fflush(stdout);
    return false;
  };
  V4l2Config request = options.request;
  request.io = method;
  request.fourccs = {fourcc};
  auto opened = V4l2Camera::open(options.device);
  if (!opened) return fail(opened.error());
  V4l2Camera& camera = *opened.value();
  if (std::string error = camera.configure(request); !error.empty()) return fail(error);
  const auto& description = camera.description();
  std::printf("device: %s (%s, %s), format %s %dx%d, %.3f fps\n", description.card.c_str(),
              description.driver.c_str(), description.bus_info.c_str(),
              std::string(description.format.info.name).c_str(), description.format.width,
              description.format.height, description.format.frame_rate);
  for (const auto& control : description.controls.read_back) {
    std::printf("control read back: %s = %d\n", control.name.c_str(), control.value);
  }
  for (const auto& warning : description.controls.warnings)
    std::printf("warning: %s\n", warning.c_str());
  for (const auto& warning : description.warnings) std::printf("warning: %s\n", warning.c_str());
  if (!description.controls.gain || *description.controls.gain != *request.controls.gain) {
    return fail("gain does not read back as " + std::to_string(*request.controls.gain));
  }
  bool autogain_off = false;
  for (const auto& control : description.controls.read_back) {
    if (control.id == V4L2_CID_AUTOGAIN && control.value == 0) autogain_off = true;
  }
  if (!autogain_off) return fail("auto gain was not read back as off");

  const auto started = std::chrono::steady_clock::now();
  if (std::string error = camera.start(); !error.empty()) return fail(error);
  if (camera.io_method() != method) {
    return fail(std::string("streaming used ") +
                flutterscan::capture::v4l2_io_method_name(camera.io_method()));
  }
  std::int64_t previous_ns = 0, first_ns = 0;
  std::uint32_t first_sequence = 0, previous_sequence = 0;
  V4l2TimestampSource source = V4l2TimestampSource::kEndOfFrame;
  const std::size_t image_size = description.format.image_size;
  for (int i = 0; i < options.frames; ++i) {
    flutterscan::capture::V4l2Frame f;
    std::string error;
    const auto got = camera.next_frame(f, 2000, error);
    if (got == flutterscan::capture::V4l2Wait::kTimeout) {
      return fail("frame " + std::to_string(i) + ": none within 2 s");
    }
    if (got != flutterscan::capture::V4l2Wait::kFrame) {
      return fail("frame " + std::to_string(i) + ": " + error);
    }
    if (i == 0) {
      first_sequence = f.sequence;
      first_ns = f.timestamp_ns;
      source = f.timestamp_source;
    } else {
      if (f.sequence != previous_sequence + 1) {
        return fail("sequence " + std::to_string(previous_sequence) + " followed by " +
                    std::to_string(f.sequence));
      }
      if (f.timestamp_ns <= previous_ns) {
        return fail("timestamp of frame " + std::to_string(i) + " not after the previous one");
      }
    }
    if (f.clock != V4l2Clock::kMonotonic) return fail("timestamps not on the monotonic clock");
    if (f.data.size() < image_size) {
      return fail("frame " + std::to_string(i) + " has " + std::to_string(f.data.size()) +
                  " bytes, expected " + std::to_string(image_size));
    }
    bool blank = true;
    for (std::size_t b = 0; b < f.data.size() && blank; b += 61) blank = f.data[b] == f.data[0];
    if (blank) return fail("frame " + std::to_string(i) + " is uniform (no test pattern)");
    previous_sequence = f.sequence;
    previous_ns = f.timestamp_ns;
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  const auto stats = camera.stats();
  camera.stop();
  if (stats.dropped != 0 || stats.corrupt != 0) {
    return fail("dropped " + std::to_string(stats.dropped) + ", corrupt " +
                std::to_string(stats.corrupt));
  }
  // Frame rate from the driver's own timestamps; the wall time includes start-up.
  const double measured_fps = static_cast<double>(options.frames - 1) /
                              (static_cast<double>(previous_ns - first_ns) * 1e-9);
  std::printf(
      "V4L2-VM-RESULT io=%s format=%s PASS frames=%llu dropped=%llu corrupt=%llu sequence=%u..%u "
      "clock=monotonic timestamp=%s %s %dx%d fps_set=%.3f fps_measured=%.2f gain=%d "
      "wall_s=%.2f\n",
      io, format_name.c_str(), static_cast<unsigned long long>(stats.frames),
      static_cast<unsigned long long>(stats.dropped),
      static_cast<unsigned long long>(stats.corrupt), first_sequence, previous_sequence,
      source == V4l2TimestampSource::kStartOfExposure ? "start-of-exposure" : "end-of-frame",
      std::string(description.format.info.name).c_str(), description.format.width,
      description.format.height, description.format.frame_rate, measured_fps,
      *description.controls.gain, seconds);
  std::fflush(stdout);
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  if (!parse(argc, argv, options)) {
    usage();
    return 2;
  }
  bool all_passed = true;
  for (std::uint32_t fourcc : options.formats) {
    for (V4l2IoMethod method : options.methods) {
      all_passed = check(options, fourcc, method) && all_passed;
    }
  }
  return all_passed ? 0 : 1;
}
