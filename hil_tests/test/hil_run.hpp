#pragma once
// Running one program under the HIL harness from a test: the harness's
// options, the program's argv, its exit status and output, and the board's
// JSON records; plus helpers to read the records (LED timeline, reports).

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

namespace flutterscan::hil::test {

/// \brief What one harness run produced.
struct HarnessRun {
  int exit_code = -1;     ///< the harness's (= the program's, 77: umockdev cannot run)
  std::string output;     ///< the program's and the harness's stdout and stderr, merged
  nlohmann::json record;  ///< the board's records (empty if none were written)
  double seconds = 0;     ///< wall time of the run
};

/// \brief Runs `program` under the harness with `harness_options`; records go
/// to a file in `work_dir`.
HarnessRun run_harness(const std::vector<std::string>& harness_options,
                       const std::vector<std::string>& program, const std::string& work_dir);

/// \brief Runs `argv` (no harness) and returns its exit status and merged output.
std::pair<int, std::string> run_plain(const std::vector<std::string>& argv);

/// \brief A test's own directory under the temp directory, removed with the
/// object when the test has not failed (a failed test's stays, its path printed).
class WorkDir {
 public:
  explicit WorkDir(std::filesystem::path path) : path_(std::move(path)) {}
  WorkDir(const WorkDir&) = delete;
  WorkDir& operator=(const WorkDir&) = delete;
  ~WorkDir();
  const std::string& path() const { return path_text_; }
  /// \brief The path, wherever a test passes it as a string.
  operator const std::string&() const { return path_text_; }

 private:
  std::filesystem::path path_;
  std::string path_text_ = path_.string();
};

/// \brief A fresh, empty directory for one test's files.
WorkDir make_work_dir(const std::string& name);

/// \brief The LED mask timeline: (time, LEDs on after the write), in time order.
std::vector<std::pair<std::uint64_t, std::uint8_t>> led_timeline(const nlohmann::json& record);

/// \brief LEDs on at `time_us` (the last write at or before it; 0 before the first).
std::uint8_t mask_at(const std::vector<std::pair<std::uint64_t, std::uint8_t>>& timeline,
                     std::uint64_t time_us);

/// \brief The IN reports of the record that are exposure events, in order.
std::vector<nlohmann::json> exposure_events(const nlohmann::json& record);

/// \brief "key=value" of the first output line starting with `key=`, or "".
std::string output_value(const std::string& output, const std::string& key);

/// \brief The masks of a code's digit string ('1' -> 1, '2' -> 2, '4' -> 4).
std::vector<std::uint8_t> code_masks(const std::string& digits);

}  // namespace flutterscan::hil::test
