#include "hil_run.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

extern char** environ;

namespace flutterscan::hil::test {

namespace {

std::string slurp(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace

std::pair<int, std::string> run_plain(const std::vector<std::string>& argv) {
  const std::string out_path =
      std::filesystem::temp_directory_path() /
      ("hil_out_" + std::to_string(getpid()) + "_" +
       std::to_string(std::chrono::steady_clock::now().time_since_epoch().count()));
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, out_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                   0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  std::vector<std::string> copy = argv;
  std::vector<char*> args;
  for (std::string& a : copy) args.push_back(a.data());
  args.push_back(nullptr);
  pid_t pid = -1;
  const int rc = posix_spawnp(&pid, args[0], &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) return {-1, "cannot start " + argv[0]};
  int status = 0;
  waitpid(pid, &status, 0);
  std::string output = slurp(out_path);
  std::filesystem::remove(out_path);
  const int code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  return {code, output};
}

HarnessRun run_harness(const std::vector<std::string>& harness_options,
                       const std::vector<std::string>& program, const std::string& work_dir) {
  const std::string record_path = work_dir + "/record.json";
  std::filesystem::remove(record_path);
  std::vector<std::string> argv{HIL_HARNESS, "--record", record_path};
  argv.insert(argv.end(), harness_options.begin(), harness_options.end());
  argv.push_back("--");
  argv.insert(argv.end(), program.begin(), program.end());
  const auto start = std::chrono::steady_clock::now();
  auto [code, output] = run_plain(argv);
  HarnessRun run;
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  run.exit_code = code;
  run.output = std::move(output);
  if (std::filesystem::exists(record_path)) {
    std::ifstream in(record_path);
    run.record = nlohmann::json::parse(in, nullptr, false);
  }
  return run;
}

WorkDir::~WorkDir() {
  if (::testing::Test::HasFailure()) {
    std::printf("work directory kept for a look: %s\n", path_text_.c_str());
    return;
  }
  std::error_code ignored;
  std::filesystem::remove_all(path_, ignored);
}

WorkDir make_work_dir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("flutterscan_hil_" + name + "_" + std::to_string(getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return WorkDir(dir);
}

std::vector<std::pair<std::uint64_t, std::uint8_t>> led_timeline(const nlohmann::json& record) {
  std::vector<std::pair<std::uint64_t, std::uint8_t>> out;
  for (const auto& t : record.at("led_transitions"))
    out.emplace_back(t.at(0).get<std::uint64_t>(), t.at(1).get<std::uint8_t>());
  std::stable_sort(out.begin(), out.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  return out;
}

std::uint8_t mask_at(const std::vector<std::pair<std::uint64_t, std::uint8_t>>& timeline,
                     std::uint64_t time_us) {
  std::uint8_t mask = 0;
  for (const auto& [t, m] : timeline) {
    if (t > time_us) break;
    mask = m;
  }
  return mask;
}

std::vector<nlohmann::json> exposure_events(const nlohmann::json& record) {
  std::vector<nlohmann::json> out;
  for (const auto& r : record.at("in_reports"))
    if (r.at("command").get<int>() == 0x80) out.push_back(r);
  return out;
}

std::string output_value(const std::string& output, const std::string& key) {
  std::istringstream in(output);
  std::string line;
  while (std::getline(in, line))
    if (line.rfind(key + "=", 0) == 0) return line.substr(key.size() + 1);
  return "";
}

std::vector<std::uint8_t> code_masks(const std::string& digits) {
  std::vector<std::uint8_t> out;
  for (char c : digits) out.push_back(static_cast<std::uint8_t>(c - '0'));
  return out;
}

}  // namespace flutterscan::hil::test
