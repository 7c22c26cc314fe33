#pragma once
// Helpers for the session tests: a scratch folder, a small, fast sim session
// configuration and reading a session folder back.

#include <gtest/gtest.h>
#include <unistd.h>
#include <nlohmann/json.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "session/session_config.hpp"

namespace flutterscan::session::testing {

/// \brief A fresh, empty folder under the temp directory (named for the test
/// and this process: runs in other worktrees do not share it), removed with
/// everything in it when the test has not failed (a failed test's stays, its
/// path printed).
class ScratchFolder {
 public:
  explicit ScratchFolder(const std::string& name)
      : path_(std::filesystem::temp_directory_path() /
              ("flutterscan_session_" + name + "_" + std::to_string(::getpid()))) {
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~ScratchFolder() {
    if (::testing::Test::HasFailure()) {
      std::printf("session folder kept for a look: %s\n", path_.c_str());
      return;
    }
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  ScratchFolder(const ScratchFolder&) = delete;
  ScratchFolder& operator=(const ScratchFolder&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

/// \brief A sim session of `frames` exposures at 640x240 (a label every ~31 frames of belt),
/// nominal noise (3000 e-, 4 e- read noise), written straight into `out`.
inline SessionConfig small_sim_config(const std::filesystem::path& out, int frames) {
  SessionConfig c;
  c.camera.spec = "sim";
  c.camera.options = {{"width", "640"},
                      {"height", "240"},
                      {"tile_width", "420"},
                      {"gap", "100"},
                      {"speed_px_per_s", "10000"},
                      {"counts_per_px", "2"},
                      {"max_frames", std::to_string(frames)}};
  c.controller.spec = "sim";
  c.optics.px_per_count = 0.5;
  c.output.dir = out.string();
  c.output.timestamped_subfolder = false;
  c.output.keep_first_frames = 3;
  return c;
}

/// \brief Every line of a JSON-lines file, parsed (a line that does not parse fails the caller's
/// check through `bad_lines`).
inline std::vector<nlohmann::json> read_jsonl(const std::filesystem::path& path, int& bad_lines) {
  std::vector<nlohmann::json> lines;
  std::ifstream in(path);
  std::string line;
  bad_lines = 0;
  while (std::getline(in, line)) {
    auto parsed = nlohmann::json::parse(line, nullptr, false);
    if (parsed.is_discarded())
      ++bad_lines;
    else
      lines.push_back(parsed);
  }
  return lines;
}

/// \brief The lines of session.jsonl that are about frames (not an object's result).
inline std::vector<nlohmann::json> frame_lines(const std::vector<nlohmann::json>& lines) {
  std::vector<nlohmann::json> frames;
  for (const auto& l : lines)
    if (!l.contains("object_result")) frames.push_back(l);
  return frames;
}

/// \brief The object results in session.jsonl, in the order they were published.
inline std::vector<nlohmann::json> object_lines(const std::vector<nlohmann::json>& lines) {
  std::vector<nlohmann::json> objects;
  for (const auto& l : lines)
    if (l.contains("object_result")) objects.push_back(l["object_result"]);
  return objects;
}

inline int count_flag(const std::vector<nlohmann::json>& lines, const std::string& flag) {
  int n = 0;
  for (const auto& l : lines)
    if (l.contains("flags"))
      for (const auto& f : l["flags"])
        if (f == flag) ++n;
  return n;
}

}  // namespace flutterscan::session::testing
