// `flutterscan replay` through the real binary (issue 19, item 2), on a demo
// session made once for the suite: every read of the kept frames reads again
// (exit 0); frames overwritten with a flat image no longer read (exit 1, named);
// a read the session's log does not have is reported as read now; bad input
// (no folder, no session.jsonl, no frames, a frame without descriptor or
// without its line) exits 2 naming what is missing; optics other than the
// defaults need --config.
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

struct Ran {
  int exit = -1;
  std::string out, err;
};

std::string read_text(const fs::path& path) {
  std::ifstream in(path);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

/// Runs the binary with `args`, stdout and stderr through files in `scratch`.
Ran flutterscan(const std::vector<std::string>& args, const fs::path& scratch) {
  const fs::path out = scratch / "stdout.txt", err = scratch / "stderr.txt";
  const pid_t pid = ::fork();
  if (pid == 0) {
    if (!std::freopen(out.c_str(), "w", stdout) || !std::freopen(err.c_str(), "w", stderr))
      _exit(126);
    std::vector<std::string> copies = args;
    std::string binary = FLUTTERSCAN_BINARY;
    std::vector<char*> argv{binary.data()};
    for (auto& a : copies) argv.push_back(a.data());
    argv.push_back(nullptr);
    ::execv(binary.c_str(), argv.data());
    _exit(127);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  Ran r;
  r.exit = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  r.out = read_text(out);
  r.err = read_text(err);
  return r;
}

std::vector<json> read_jsonl(const fs::path& path) {
  std::vector<json> lines;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) lines.push_back(json::parse(line));
  return lines;
}

void write_jsonl(const fs::path& path, const std::vector<json>& lines) {
  std::ofstream out(path);
  for (const json& line : lines) out << line.dump() << "\n";
}

/// The kept frames' names (fNNNNNNNN) of a session folder.
std::vector<std::string> kept_frames(const fs::path& session) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(session / "frames")) {
    const std::string name = entry.path().filename().string();
    if (name.size() == 13 && name.ends_with(".png")) names.push_back(name.substr(0, 9));
  }
  std::sort(names.begin(), names.end());
  return names;
}

/// The kept frames whose session.jsonl line has a code read, with their line.
std::map<std::string, json> kept_frames_with_reads(const fs::path& session) {
  std::set<std::uint64_t> kept;
  for (const auto& name : kept_frames(session)) kept.insert(std::stoull(name.substr(1)));
  std::map<std::string, json> out;
  for (const json& line : read_jsonl(session / "session.jsonl")) {
    if (!line.contains("sequence") || !kept.count(line["sequence"].get<std::uint64_t>())) continue;
    if (line.value("decoded", json::array()).empty()) continue;
    char name[32];
    std::snprintf(name, sizeof name, "f%08llu",
                  static_cast<unsigned long long>(line["sequence"].get<std::uint64_t>()));
    out[name] = line;
  }
  return out;
}

/// A demo session of 10 frames (all kept: keep_first_frames is 10), made once
/// per test process; each test works on its own copy.
class ReplayCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    root_ = fs::temp_directory_path() / ("flutterscan_replay_" + std::to_string(::getpid()));
    fs::remove_all(root_);
    fs::create_directories(root_ / "demo");
    const Ran demo = flutterscan(
        {"demo", "--frames", "10", "--out", (root_ / "demo").string(), "--no-progress"}, root_);
    ASSERT_EQ(demo.exit, 0) << demo.err;
    for (const auto& entry : fs::directory_iterator(root_ / "demo"))
      if (entry.is_directory()) session_ = entry.path();
    ASSERT_FALSE(session_.empty());
  }
  static void TearDownTestSuite() {
    if (!failed_) fs::remove_all(root_);
  }
  void SetUp() override {
    ASSERT_FALSE(session_.empty());
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    scratch_ = root_ / info->name();
    fs::remove_all(scratch_);
    fs::create_directories(scratch_);
    copy_ = scratch_ / "session";
    fs::copy(session_, copy_, fs::copy_options::recursive);
  }
  void TearDown() override {
    if (HasFailure()) {
      failed_ = true;
      std::printf("replay test folder kept for a look: %s\n", scratch_.c_str());
    }
  }
  Ran replay(std::vector<std::string> args) {
    args.insert(args.begin(), "replay");
    return flutterscan(args, scratch_);
  }

  static inline fs::path root_, session_;
  static inline bool failed_ = false;
  fs::path scratch_, copy_;
};

TEST_F(ReplayCli, EveryReadInTheDemosKeptFramesReadsAgain) {
  const auto with_reads = kept_frames_with_reads(copy_);
  ASSERT_FALSE(with_reads.empty()) << "the demo kept no frame with a read";
  const Ran r = replay({copy_.string(), "--json"});
  ASSERT_EQ(r.exit, 0) << r.out << r.err;
  const json j = json::parse(r.out);
  EXPECT_EQ(j["frames"].size(), kept_frames(copy_).size());
  EXPECT_TRUE(j["config"].is_null());
  std::size_t reads_then = 0;
  for (const auto& [name, line] : with_reads) reads_then += line["decoded"].size();
  EXPECT_EQ(j["total"]["reads_then"], reads_then);
  EXPECT_EQ(j["total"]["read_again"], reads_then);
  EXPECT_EQ(j["total"]["no_longer_read"], 0);
  EXPECT_TRUE(j["total"]["regressed_frames"].empty());
  for (const json& f : j["frames"]) EXPECT_TRUE(f["no_longer_reads"].empty()) << f.dump();
  // The text: the config said, a line per frame, the total.
  const Ran text = replay({copy_.string()});
  ASSERT_EQ(text.exit, 0) << text.out << text.err;
  EXPECT_NE(text.out.find("config   the defaults"), std::string::npos) << text.out;
  for (const auto& name : kept_frames(copy_))
    EXPECT_NE(text.out.find(name + "  "), std::string::npos) << name << "\n" << text.out;
  EXPECT_NE(text.out.find(std::to_string(reads_then) + " of " + std::to_string(reads_then) +
                          " reads read again, 0 no longer read"),
            std::string::npos)
      << text.out;
}

TEST_F(ReplayCli, FramesAlteredToFailExitOneNamingThem) {
  const auto with_reads = kept_frames_with_reads(copy_);
  ASSERT_FALSE(with_reads.empty());
  for (const auto& [name, line] : with_reads) {
    // A flat grey image of the same size and depth: nothing to read on it.
    const std::string path = (copy_ / "frames" / (name + ".png")).string();
    const cv::Mat frame = cv::imread(path, cv::IMREAD_UNCHANGED);
    ASSERT_FALSE(frame.empty()) << path;
    const cv::Mat flat(frame.size(), frame.type(), cv::Scalar::all(1000));
    ASSERT_TRUE(cv::imwrite(path, flat)) << path;
  }
  const Ran r = replay({copy_.string()});
  EXPECT_EQ(r.exit, 1) << r.out << r.err;
  for (const auto& [name, line] : with_reads) {
    EXPECT_NE(r.err.find(name), std::string::npos) << name << "\n" << r.err;
    for (const json& code : line["decoded"])
      EXPECT_NE(r.out.find("no longer reads  " + code["text"].get<std::string>()),
                std::string::npos)
          << r.out;
  }
  // Frames that read nothing then are not named.
  for (const auto& name : kept_frames(copy_)) {
    if (with_reads.count(name)) continue;
    EXPECT_EQ(r.err.find(name), std::string::npos) << r.err;
  }
}

TEST_F(ReplayCli, AReadTheSessionMissedIsReportedAsReadNowAndUnknownFieldsAreIgnored) {
  const auto with_reads = kept_frames_with_reads(copy_);
  ASSERT_FALSE(with_reads.empty());
  const std::string missed = with_reads.begin()->first;
  const std::string value = with_reads.begin()->second["decoded"][0]["text"];
  std::vector<json> lines = read_jsonl(copy_ / "session.jsonl");
  for (json& line : lines) {
    // Fields a later read record may add, on the line and on each code read.
    line["read_record_version"] = 2;
    for (json& code : line["decoded"]) {
      code["symbology_identifier"] = "]C0";
      code["corners"] = json::array({1, 2, 3, 4, 5, 6, 7, 8});
      code["quality"] = {{"grade", "B"}};
    }
    if (line.contains("sequence") && line["sequence"] == std::stoull(missed.substr(1)))
      line["decoded"] = json::array();  // the session "missed" it: a NO-READ label then
  }
  write_jsonl(copy_ / "session.jsonl", lines);
  const Ran r = replay({copy_.string()});
  ASSERT_EQ(r.exit, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("  reads now        " + value), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("(NO-READ then)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("0 no longer read"), std::string::npos) << r.out;
}

TEST_F(ReplayCli, BadInputExitsTwoNamingWhatIsMissing) {
  struct Case {
    std::string what;
    fs::path folder;
    std::string named;
  };
  std::vector<Case> cases;
  cases.push_back({"no such folder", scratch_ / "nowhere", (scratch_ / "nowhere").string()});
  const fs::path no_log = scratch_ / "no_log";
  fs::create_directories(no_log / "frames");
  cases.push_back({"no session.jsonl", no_log, (no_log / "session.jsonl").string()});
  const fs::path no_frames = scratch_ / "no_frames";
  fs::create_directories(no_frames);
  fs::copy_file(copy_ / "session.jsonl", no_frames / "session.jsonl");
  cases.push_back({"no frames folder", no_frames, (no_frames / "frames").string()});
  const fs::path empty_frames = scratch_ / "empty_frames";
  fs::create_directories(empty_frames / "frames");
  fs::copy_file(copy_ / "session.jsonl", empty_frames / "session.jsonl");
  cases.push_back({"no frame in frames/", empty_frames, (empty_frames / "frames").string()});
  const std::string first = kept_frames(copy_).front();
  const fs::path no_descriptor = scratch_ / "no_descriptor";
  fs::copy(copy_, no_descriptor, fs::copy_options::recursive);
  fs::remove(no_descriptor / "frames" / (first + ".json"));
  cases.push_back({"a frame without descriptor", no_descriptor,
                   (no_descriptor / "frames" / (first + ".json")).string()});
  const fs::path no_line = scratch_ / "no_line";
  fs::copy(copy_, no_line, fs::copy_options::recursive);
  std::vector<json> lines = read_jsonl(no_line / "session.jsonl");
  std::erase_if(lines, [&](const json& l) {
    return l.contains("sequence") && l["sequence"] == std::stoull(first.substr(1));
  });
  write_jsonl(no_line / "session.jsonl", lines);
  cases.push_back({"a frame without its line", no_line,
                   (no_line / "frames" / (first + ".png")).string() + "' (sequence"});
  for (const Case& c : cases) {
    const Ran r = replay({c.folder.string()});
    EXPECT_EQ(r.exit, 2) << c.what << ": " << r.out << r.err;
    EXPECT_NE(r.err.find(c.named), std::string::npos) << c.what << ": " << r.err;
    EXPECT_TRUE(r.out.empty()) << c.what << ": " << r.out;
  }
}

// A kept frame's descriptor with a field of any JSON type, through both readers of a
// session's frames (`replay` and `scan --camera files:`): exit 0, 1 or 2, never a
// signal; a field that is read is refused, naming it and the file. Every field of
// the first kept frame's descriptor (those the files camera reads through both
// commands, the capture model's through replay, which reads the model), and a few
// on the last kept frame (refused by next_frame, not open).
TEST_F(ReplayCli, ADescriptorFieldOfAnyTypeExitsZeroOneOrTwoNamingIt) {
  const std::vector<std::string> frames = kept_frames(copy_);
  const json original = json::parse(read_text(copy_ / "frames" / (frames.front() + ".json")));
  ASSERT_TRUE(original.contains("capture")) << original.dump();
  // The fields the files camera reads, and the session's other capture fields (the
  // labels' values are written only for a frame with labels: added where absent).
  std::vector<std::string> camera_fields = {"bit_depth", "bayer", "capture"};
  json capture = original["capture"];
  capture.emplace("truth", json::array());
  capture.emplace("truth_in_view", json::array());
  for (const auto& [key, value] : capture.items()) camera_fields.push_back("capture." + key);
  std::vector<std::string> model_fields;
  for (const auto& [key, value] : original.items())
    if (key != "bit_depth" && key != "bayer" && key != "capture") model_fields.push_back(key);
  ASSERT_GT(model_fields.size(), 15u) << original.dump();
  // A string, null, an array, an object, and for the files camera's fields (whole
  // numbers, strings or lists) a negative fraction.
  const std::vector<json> values = {"x", nullptr, json::array({1}), json{{"a", 1}}, -1.5};

  struct Run {
    std::string frame, field;
    json value;
    bool scan;
    bool refused;  ///< the value is one the reader must refuse
  };
  std::vector<Run> runs;
  for (const json& value : values) {
    for (const std::string& field : camera_fields) {
      // Not read by either command: the exposure counter (logged, not replayed).
      const bool read = field != "capture.exposure_counter";
      const bool valid = (field == "bayer" && value.is_null()) ||
                         (field == "capture" && value.is_object());  // unknown fields ignored
      for (const bool scan : {false, true})
        runs.push_back({frames.front(), field, value, scan, read && !valid});
    }
    if (!value.is_number())
      for (const std::string& field : model_fields)
        runs.push_back({frames.front(), field, value, false, true});
  }
  for (const char* field : {"bit_depth", "capture.sequence", "capture.truth"})
    for (const bool scan : {false, true}) runs.push_back({frames.back(), field, "x", scan, true});

  for (const Run& run : runs) {
    const fs::path folder = scratch_ / "mutated";
    fs::remove_all(folder);
    fs::copy(copy_, folder, fs::copy_options::recursive);
    const fs::path descriptor = folder / "frames" / (run.frame + ".json");
    json d = json::parse(read_text(descriptor));
    std::string pointer = "/" + run.field;
    std::replace(pointer.begin(), pointer.end(), '.', '/');
    d[json::json_pointer(pointer)] = run.value;
    std::ofstream(descriptor) << d.dump(2);
    const std::string what = std::string(run.scan ? "scan" : "replay") + ", " + run.frame + " " +
                             run.field + " = " + run.value.dump();
    const Ran r = run.scan
                      ? flutterscan({"scan", "--camera", "files:" + (folder / "frames").string(),
                                     "--out", (scratch_ / "scans").string(), "--no-progress"},
                                    scratch_)
                      : replay({folder.string()});
    EXPECT_TRUE(r.exit == 0 || r.exit == 1 || r.exit == 2) << what << ": exit " << r.exit << "\n"
                                                           << r.err;
    if (run.refused) {
      EXPECT_NE(r.exit, 0) << what << ": " << r.out;
    }
    if (r.exit == 1 || r.exit == 2) {
      // The field by its last name ('sequence' in capture.sequence) and the frame's
      // files (fNNNNNNNN.json, or .png where replay compares the frame's optics).
      const std::string name = run.field.substr(run.field.rfind('.') + 1);
      EXPECT_NE(r.err.find(name), std::string::npos) << what << ": " << r.err;
      const std::string stem = (folder / "frames" / run.frame).string() + ".";
      EXPECT_NE(r.err.find(stem), std::string::npos) << what << ": " << r.err;
    }
  }
}

TEST_F(ReplayCli, OpticsOtherThanTheDefaultsNeedTheSessionsConfig) {
  const std::string first = kept_frames(copy_).front();
  const fs::path descriptor = copy_ / "frames" / (first + ".json");
  json d = json::parse(read_text(descriptor));
  d["black_level_dn"] = 60.0;
  std::ofstream(descriptor) << d.dump(2);
  const Ran r = replay({copy_.string()});
  EXPECT_EQ(r.exit, 2) << r.out << r.err;
  for (const char* named : {"black_level_dn (config 64, frame 60)", "--config", first.c_str()})
    EXPECT_NE(r.err.find(named), std::string::npos) << named << "\n" << r.err;
  // With the config given, the replay goes on under it and says the optics differ.
  std::ofstream(scratch_ / "line.toml") << "# the session's defaults\n";
  const Ran with_config = replay({copy_.string(), "--config", (scratch_ / "line.toml").string()});
  EXPECT_NE(with_config.exit, 2) << with_config.out << with_config.err;
  EXPECT_NE(with_config.err.find("warning: the config's optics differ"), std::string::npos)
      << with_config.err;
  EXPECT_NE(with_config.out.find("config   " + (scratch_ / "line.toml").string()),
            std::string::npos)
      << with_config.out;
}

}  // namespace
