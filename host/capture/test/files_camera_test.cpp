// The files backend: replays frames with descriptors in name order, keeps
// their recorded sequence numbers and timestamps, counts sequence gaps, and
// refuses folders it cannot replay, naming them.
#include "capture/files_camera.hpp"

#include <gtest/gtest.h>
#include <unistd.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include <filesystem>
#include <fstream>

#include "capture/frame_pixels.hpp"

namespace flutterscan::capture {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

/// A fresh folder under the temp directory, removed with the object.
class ScratchFolder {
 public:
  explicit ScratchFolder(const std::string& name)
      : path_(fs::temp_directory_path() /
              ("flutterscan_files_" + name + "_" + std::to_string(::getpid()))) {
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~ScratchFolder() {
    std::error_code ignored;
    fs::remove_all(path_, ignored);
  }
  ScratchFolder(const ScratchFolder&) = delete;
  ScratchFolder& operator=(const ScratchFolder&) = delete;
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

/// A 16-bit RGB frame whose red value is `red` everywhere, with a descriptor.
void write_frame(const fs::path& folder, const std::string& stem, std::uint16_t red,
                 std::uint64_t sequence, std::int64_t timestamp_ns) {
  cv::Mat bgr(4, 6, CV_16UC3, cv::Scalar(7, 500, red));
  ASSERT_TRUE(cv::imwrite((folder / (stem + ".png")).string(), bgr));
  nlohmann::json descriptor = {
      {"format", "flutterscan-capture"},
      {"version", 1},
      {"bit_depth", 12},
      {"capture", {{"sequence", sequence}, {"timestamp_ns", timestamp_ns}}}};
  std::ofstream(folder / (stem + ".json")) << descriptor.dump();
}

TEST(FilesCamera, ReplaysInNameOrderWithRecordedIdsAndCountsGaps) {
  const ScratchFolder scratch("replay");
  const fs::path& folder = scratch.path();
  write_frame(folder, "f002", 300, 11, 2000);
  write_frame(folder, "f001", 100, 10, 1000);
  write_frame(folder, "f003", 900, 13, 4000);
  cv::imwrite((folder / "f001.truth.png").string(), cv::Mat(4, 6, CV_16UC1, cv::Scalar(1)));

  std::string error;
  auto camera = make_camera("files:" + folder.string(), {}, error);
  ASSERT_TRUE(camera) << error;
  ASSERT_EQ(camera->open(), "");
  ASSERT_EQ(camera->configure({}), "");
  EXPECT_EQ(camera->format().pixel_format, PixelFormat::kRgb16);
  EXPECT_EQ(camera->format().bit_depth, 12);
  ASSERT_EQ(camera->start(), "");

  std::vector<Frame> frames;
  Frame frame;
  while (camera->next_frame(frame, 10ms, error) == FrameWait::kFrame) frames.push_back(frame);
  ASSERT_EQ(frames.size(), 3u);  // the truth image has no descriptor: skipped
  EXPECT_EQ(frames[0].sequence, 10u);
  EXPECT_EQ(frames[1].sequence, 11u);
  EXPECT_EQ(frames[2].sequence, 13u);
  EXPECT_EQ(frames[2].timestamp_ns, 4000);
  EXPECT_EQ(camera->counters().frames_dropped, 1u);
  EXPECT_EQ(camera->counters().frames_delivered, 3u);

  const auto dn = frame_to_dn(frames[1]);
  ASSERT_TRUE(dn.ok()) << dn.error();
  ASSERT_EQ(dn.value().channel_count(), 3);
  EXPECT_EQ(dn.value().channels[0].at(5, 3), 300.0f);
  EXPECT_EQ(dn.value().channels[1].at(0, 0), 500.0f);
  EXPECT_EQ(dn.value().channels[2].at(2, 1), 7.0f);
  EXPECT_FALSE(frames[0].descriptor_json.empty());
}

TEST(FilesCamera, RefusesAFolderWithoutFrames) {
  const ScratchFolder scratch("empty");
  const fs::path& folder = scratch.path();
  auto camera = make_files_camera(folder.string());
  const std::string problem = camera->open();
  EXPECT_NE(problem.find(folder.string()), std::string::npos) << problem;
  EXPECT_NE(problem.find("no frame"), std::string::npos) << problem;
  auto missing = make_files_camera((folder / "nope").string());
  EXPECT_NE(missing->open().find("not a folder"), std::string::npos);
}

TEST(FilesCamera, RefusesAnotherSizeThanRecorded) {
  const ScratchFolder scratch("size");
  const fs::path& folder = scratch.path();
  write_frame(folder, "a", 1, 0, 0);
  auto camera = make_files_camera(folder.string());
  ASSERT_EQ(camera->open(), "");
  CameraSettings wanted;
  wanted.width = 1920;
  EXPECT_NE(camera->configure(wanted).find("1920"), std::string::npos);
}

TEST(FramePixels, RefusesDataShorterThanTheFormat) {
  Frame frame;
  frame.sequence = 4;
  frame.format = {10, 10, PixelFormat::kRgb8, 8, 0};
  frame.data.resize(299);
  const auto dn = frame_to_dn(frame);
  ASSERT_FALSE(dn.ok());
  EXPECT_NE(dn.error().find("frame 4"), std::string::npos) << dn.error();
}

TEST(CameraRegistry, UnknownSchemeNamesTheKnownOnes) {
  std::string error;
  EXPECT_FALSE(make_camera("gopro:1", {}, error));
  EXPECT_NE(error.find("gopro"), std::string::npos);
  EXPECT_NE(error.find("files"), std::string::npos);
}

}  // namespace
}  // namespace flutterscan::capture
