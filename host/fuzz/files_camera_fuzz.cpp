// libFuzzer target: a kept frame's capture descriptor through the files camera
// (`flutterscan scan --camera files:DIR`, `flutterscan replay`), then through
// from_descriptor as replay reads it.
//
// Input: byte 0 picks the frames (bit 0: 16-bit, else 8-bit; bit 1: RGB, else
// grey) and which of two frames gets the descriptor (bit 2: the second, read
// by next_frame; else the first, read by open); the rest is the descriptor's
// text, written as it is beside the frame. The other frame has a valid one.
// The frames are 6 x 4 px PNGs in a folder under the temp directory, made once.
// Oracles: nothing throws; a refusal names the descriptor file; a frame played
// is the image's size and format with a bit depth of 1 to the container's 16,
// and its descriptor_json parses, for from_descriptor to accept or refuse with
// a message.

#include <unistd.h>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include <array>
#include <filesystem>
#include <fstream>

#include "capture/files_camera.hpp"
#include "fuzz_support.hpp"
#include "imaging/capture_descriptor.hpp"

using namespace flutterscan;

namespace {

namespace fs = std::filesystem;

constexpr int kWidth = 6, kHeight = 4;

/// The frames' folders, one per byte-0 mode, removed at exit.
class Folders {
 public:
  Folders()
      : root_(fs::temp_directory_path() /
              ("flutterscan_files_camera_fuzz_" + std::to_string(::getpid()))) {}
  ~Folders() {
    std::error_code ignored;
    fs::remove_all(root_, ignored);
  }
  Folders(const Folders&) = delete;
  Folders& operator=(const Folders&) = delete;

  /// The folder of `mode` (bits 0-1) with its two images, made on first use.
  const fs::path& folder(int mode) {
    fs::path& dir = made_[static_cast<std::size_t>(mode)];
    if (!dir.empty()) return dir;
    dir = root_ / std::to_string(mode);
    fs::create_directories(dir);
    const int depth = (mode & 1) != 0 ? CV_16U : CV_8U;
    const int channels = (mode & 2) != 0 ? 3 : 1;
    for (const char* stem : {"f1", "f2"}) {
      cv::Mat image(kHeight, kWidth, CV_MAKETYPE(depth, channels));
      for (int y = 0; y < kHeight; ++y)
        for (int x = 0; x < kWidth * channels; ++x)
          if (depth == CV_16U)
            image.ptr<std::uint16_t>(y)[x] = static_cast<std::uint16_t>(300 * (x + y));
          else
            image.ptr<std::uint8_t>(y)[x] = static_cast<std::uint8_t>(20 * (x + y));
      cv::imwrite((dir / (std::string(stem) + ".png")).string(), image);
    }
    return dir;
  }

 private:
  fs::path root_;
  std::array<fs::path, 4> made_;
};

/// A descriptor as a session keeps it, but for the capture model's fields
/// (which the files camera does not read).
const char* kValidDescriptor =
    R"({"format":"flutterscan-capture","version":1,"bit_depth":8,"bayer":null,)"
    R"("capture":{"sequence":3,"timestamp_ns":100,"truth":["4006381333931"]}})";

void check_frame(const capture::Frame& frame, int mode) {
  const bool wide = (mode & 1) != 0, rgb = (mode & 2) != 0;
  FUZZ_CHECK(frame.format.width == kWidth && frame.format.height == kHeight,
             std::to_string(frame.format.width) + " x " + std::to_string(frame.format.height));
  FUZZ_CHECK(frame.format.bit_depth >= 1 && frame.format.bit_depth <= 16,
             "bit depth " + std::to_string(frame.format.bit_depth));
  const auto format = frame.format.pixel_format;
  if (rgb)
    FUZZ_CHECK(format == (wide ? capture::PixelFormat::kRgb16 : capture::PixelFormat::kRgb8),
               capture::pixel_format_name(format));
  else
    FUZZ_CHECK(format == (wide ? capture::PixelFormat::kMono16 : capture::PixelFormat::kMono8) ||
                   format == (wide ? capture::PixelFormat::kBayerRggb16
                                   : capture::PixelFormat::kBayerRggb8),
               capture::pixel_format_name(format));
  FUZZ_CHECK(frame.data.size() == frame.format.row_bytes * static_cast<std::size_t>(kHeight),
             "data of " + std::to_string(frame.data.size()) + " bytes");
  const auto descriptor = nlohmann::json::parse(frame.descriptor_json, nullptr, false);
  FUZZ_CHECK(descriptor.is_object(), "descriptor_json: " + frame.descriptor_json);
  const auto model = imaging::from_descriptor(descriptor);
  FUZZ_CHECK(model.ok() || !model.error().empty(), "from_descriptor refused without a message");
}

/// The files camera over `folder`: every frame played, every refusal naming `named`.
void play(const fs::path& folder, const fs::path& named, int mode) {
  auto camera = capture::make_files_camera(folder.string());
  if (const std::string problem = camera->open(); !problem.empty()) {
    fuzz::trace("open refused: " + problem);
    FUZZ_CHECK(problem.find(named.string()) != std::string::npos,
               "a refusal that does not name the descriptor: " + problem);
    return;
  }
  FUZZ_CHECK(camera->configure({}).empty(), "configure refused the recorded format");
  FUZZ_CHECK(camera->start().empty(), "start refused");
  for (int played = 0;; ++played) {
    FUZZ_CHECK(played <= 2, "more frames than files");
    capture::Frame frame;
    std::string error;
    const auto wait = camera->next_frame(frame, std::chrono::milliseconds(0), error);
    if (wait == capture::FrameWait::kEnd) return;
    if (wait == capture::FrameWait::kError) {
      fuzz::trace("frame refused: " + error);
      FUZZ_CHECK(error.find(named.string()) != std::string::npos,
                 "a refusal that does not name the descriptor: " + error);
      return;
    }
    FUZZ_CHECK(wait == capture::FrameWait::kFrame, "neither a frame, an end nor an error");
    check_frame(frame, mode);
    fuzz::trace("frame " + std::to_string(frame.sequence) + " played");
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1 || size > 16 * 1024) return 0;
  static Folders folders;
  const int mode = data[0] & 3;
  const bool second = (data[0] & 4) != 0;
  const fs::path& folder = folders.folder(mode);
  const fs::path fuzzed = folder / (second ? "f2.json" : "f1.json");
  const fs::path valid = folder / (second ? "f1.json" : "f2.json");
  std::ofstream(valid, std::ios::binary | std::ios::trunc) << kValidDescriptor;
  std::ofstream(fuzzed, std::ios::binary | std::ios::trunc)
      .write(reinterpret_cast<const char*>(data + 1), static_cast<std::streamsize>(size - 1));
  try {
    play(folder, fuzzed, mode);
  } catch (const std::exception& e) {
    FUZZ_CHECK(false, std::string("an exception escaped the files camera: ") + e.what());
  }
  return 0;
}
