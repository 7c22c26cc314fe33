// The files backend: replays frames with descriptors in name order, keeps
// their recorded sequence numbers and timestamps, counts sequence gaps, and
// refuses folders it cannot replay, naming them.
#include "capture/files_camera.hpp"

#include <gtest/gtest.h>
#include <unistd.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <limits>

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

/// A descriptor as a session keeps it (frame_processing.cpp's `record`), with
/// `value` at `field` ("bit_depth", "capture.sequence", ...; a pointer path).
nlohmann::json kept_descriptor(const nlohmann::json::json_pointer& field,
                               const nlohmann::json& value) {
  nlohmann::json descriptor = {{"format", "flutterscan-capture"},
                               {"version", 1},
                               {"bit_depth", 12},
                               {"bayer", nullptr},
                               {"capture",
                                {{"sequence", 7},
                                 {"timestamp_ns", 1000},
                                 {"exposure_counter", 7},
                                 {"truth", {"4006381333931"}},
                                 {"truth_in_view", {"4006381333931"}}}}};
  descriptor[field] = value;
  return descriptor;
}

/// Whether `value` is one the files camera must accept at `field`.
bool accepted(const std::string& field, const nlohmann::json& value) {
  if (field == "bit_depth")
    return value.is_number_integer() && value.get<std::int64_t>() >= 1 &&
           value.get<std::int64_t>() <= 16;
  if (field == "bayer") return value.is_null() || value == "RGGB";
  if (field == "capture") return value.is_object();
  if (field == "capture.sequence")  // any std::uint64_t
    return value.is_number_unsigned() ||
           (value.is_number_integer() && value.get<std::int64_t>() >= 0);
  if (field == "capture.timestamp_ns")  // any std::int64_t
    return value.is_number_integer() &&
           !(value.is_number_unsigned() &&
             value.get<std::uint64_t>() > std::numeric_limits<std::int64_t>::max());
  // capture.truth, capture.truth_in_view: lists of strings.
  return value.is_array() &&
         std::all_of(value.begin(), value.end(), [](const auto& v) { return v.is_string(); });
}

// A kept frame's descriptor with any field the files camera reads of any JSON
// type: the frame is refused with a message naming the field and the file
// (open() for the first frame, next_frame for a later one), never an exception.
TEST(FilesCamera, ADescriptorFieldOfAWrongTypeIsRefusedNamingTheFieldAndTheFile) {
  using nlohmann::json;
  const std::vector<std::string> fields = {"bit_depth",
                                           "bayer",
                                           "capture",
                                           "capture.sequence",
                                           "capture.timestamp_ns",
                                           "capture.truth",
                                           "capture.truth_in_view"};
  const std::vector<json> values = {"x",
                                    "",
                                    nullptr,
                                    json::array(),
                                    json::array({1}),
                                    json::array({"a", nullptr}),
                                    json::object(),
                                    json{{"sequence", "a"}},
                                    true,
                                    0,
                                    -1,
                                    1.5,
                                    12,
                                    99,
                                    1e300,
                                    json(std::numeric_limits<std::uint64_t>::max())};
  const ScratchFolder scratch("types");
  const fs::path& folder = scratch.path();
  int refused = 0;
  for (const std::string& field : fields) {
    std::string pointer = "/" + field;
    std::replace(pointer.begin(), pointer.end(), '.', '/');
    for (const json& value : values) {
      if (accepted(field, value)) continue;
      const std::string what = field + " = " + value.dump();
      const json bad = kept_descriptor(json::json_pointer(pointer), value);
      const json good = kept_descriptor(json::json_pointer("/bit_depth"), 12);
      for (const bool first : {true, false}) {
        fs::remove_all(folder);
        fs::create_directories(folder);
        write_frame(folder, "f1", 100, 1, 1);
        write_frame(folder, "f2", 100, 2, 2);
        std::ofstream(folder / "f1.json") << (first ? bad : good).dump();
        std::ofstream(folder / "f2.json") << (first ? good : bad).dump();
        const std::string file = (folder / (first ? "f1.json" : "f2.json")).string();
        auto camera = make_files_camera(folder.string());
        std::string problem;
        try {
          problem = camera->open();
          if (!first) {
            ASSERT_EQ(problem, "") << what;
            ASSERT_EQ(camera->configure({}), "") << what;
            ASSERT_EQ(camera->start(), "") << what;
            Frame frame;
            ASSERT_EQ(camera->next_frame(frame, 10ms, problem), FrameWait::kFrame) << what;
            EXPECT_EQ(camera->next_frame(frame, 10ms, problem), FrameWait::kError) << what;
          }
        } catch (const std::exception& e) {
          ADD_FAILURE() << what << (first ? " (first frame)" : " (second frame)") << ": threw "
                        << e.what();
          continue;
        }
        EXPECT_NE(problem.find("'" + field + "'"), std::string::npos) << what << ": " << problem;
        EXPECT_NE(problem.find(file), std::string::npos) << what << ": " << problem;
        ++refused;
      }
    }
  }
  EXPECT_GT(refused, 70);  // every field met several wrong types
}

// What the descriptor's capture object says reaches the frame; without one the
// frame index and 1/30 s steps stand in, and a Bayer descriptor makes a mosaic.
TEST(FilesCamera, ReadsTheCaptureObjectAndDefaultsWithoutIt) {
  const ScratchFolder scratch("capture");
  const fs::path& folder = scratch.path();
  write_frame(folder, "f1", 100, 0, 0);
  std::ofstream(folder / "f1.json")
      << kept_descriptor(nlohmann::json::json_pointer("/capture/sequence"), 41).dump();
  cv::imwrite((folder / "f2.png").string(), cv::Mat(4, 6, CV_16UC3, cv::Scalar(9, 9, 9)));
  std::ofstream(folder / "f2.json") << nlohmann::json{{"format", "flutterscan-capture"}}.dump();
  auto camera = make_files_camera(folder.string());
  ASSERT_EQ(camera->open(), "");
  ASSERT_EQ(camera->start(), "");
  Frame first, second;
  std::string error;
  ASSERT_EQ(camera->next_frame(first, 10ms, error), FrameWait::kFrame) << error;
  ASSERT_EQ(camera->next_frame(second, 10ms, error), FrameWait::kFrame) << error;
  EXPECT_EQ(first.sequence, 41u);
  EXPECT_EQ(first.timestamp_ns, 1000);
  EXPECT_EQ(first.format.bit_depth, 12);
  EXPECT_EQ(first.truth, std::vector<std::string>{"4006381333931"});
  EXPECT_EQ(first.truth_in_view, std::vector<std::string>{"4006381333931"});
  EXPECT_EQ(second.sequence, 1u);  // the frame index
  EXPECT_EQ(second.timestamp_ns, 33'333'333);
  EXPECT_EQ(second.format.bit_depth, 16);  // the container's
  EXPECT_TRUE(second.truth.empty());

  const ScratchFolder mosaic("bayer");
  cv::imwrite((mosaic.path() / "f1.png").string(), cv::Mat(4, 6, CV_8UC1, cv::Scalar(9)));
  std::ofstream(mosaic.path() / "f1.json") << nlohmann::json{{"bayer", "RGGB"}}.dump();
  auto bayer = make_files_camera(mosaic.path().string());
  ASSERT_EQ(bayer->open(), "");
  EXPECT_EQ(bayer->format().pixel_format, PixelFormat::kBayerRggb8);
  EXPECT_EQ(bayer->format().bit_depth, 8);
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
