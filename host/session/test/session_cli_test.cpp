// The real binary: Ctrl-C (SIGINT) mid-session leaves a valid, complete
// session folder; report.html loads in headless Chromium without console
// errors, and a screenshot of it is taken; bad configuration exits 2.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <array>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <thread>

#include "session/test/session_test_support.hpp"

namespace flutterscan::session {
namespace {

namespace fs = std::filesystem;
using namespace testing;

/// Starts the binary with `args` (stdout/stderr to files in `out`); returns its pid.
pid_t spawn(const std::vector<std::string>& args, const fs::path& out) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    const std::string stdout_path = (out / "stdout.txt").string();
    const std::string stderr_path = (out / "stderr.txt").string();
    if (!std::freopen(stdout_path.c_str(), "w", stdout)) _exit(126);
    if (!std::freopen(stderr_path.c_str(), "w", stderr)) _exit(126);
    std::vector<char*> argv;
    std::string binary = FLUTTERSCAN_BINARY;
    argv.push_back(binary.data());
    std::vector<std::string> copies = args;
    for (auto& a : copies) argv.push_back(a.data());
    argv.push_back(nullptr);
    ::execv(binary.c_str(), argv.data());
    _exit(127);
  }
  return pid;
}

int wait_exit(pid_t pid) {
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

std::string read_text(const fs::path& path) {
  std::ifstream in(path);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

/// The session folder the demo made under `out`.
fs::path only_session(const fs::path& out) {
  for (const auto& entry : fs::directory_iterator(out))
    if (entry.is_directory()) return entry.path();
  return {};
}

TEST(SessionCli, SigintMidSessionLeavesAValidCompleteFolder) {
  const ScratchFolder scratch("sigint");
  const fs::path& out = scratch.path();
  const pid_t pid =
      spawn({"demo", "--frames", "100000", "--out", out.string(), "--no-progress"}, out);
  // Wait until the session has logged a few frames.
  fs::path folder;
  for (int i = 0; i < 600; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    folder = only_session(out);
    if (!folder.empty() && fs::exists(folder / "session.jsonl")) {
      int bad = 0;
      if (read_jsonl(folder / "session.jsonl", bad).size() >= 5) break;
    }
  }
  ASSERT_FALSE(folder.empty());
  ASSERT_EQ(::kill(pid, SIGINT), 0);
  const int code = wait_exit(pid);
  EXPECT_EQ(code, 0) << read_text(out / "stderr.txt");
  // Complete: summary, report, every log line whole, no temporary files left.
  const auto summary = nlohmann::json::parse(read_text(folder / "summary.json"), nullptr, false);
  ASSERT_FALSE(summary.is_discarded());
  EXPECT_EQ(summary["stopped_by"], "stop request (SIGINT)");
  EXPECT_GE(summary["frames_processed"].get<int>(), 5);
  EXPECT_TRUE(fs::exists(folder / "report.html"));
  int bad = 0;
  const auto lines = read_jsonl(folder / "session.jsonl", bad);
  EXPECT_EQ(bad, 0);
  EXPECT_EQ(static_cast<int>(lines.size()),
            summary["frames_captured"].get<int>() + summary["events_without_frame"].get<int>());
  for (const auto& entry : fs::recursive_directory_iterator(folder))
    EXPECT_EQ(entry.path().filename().string().find(".tmp"), std::string::npos) << entry.path();
  EXPECT_NE(read_text(out / "stdout.txt").find("report.html"), std::string::npos);
}

TEST(SessionCli, BadConfigurationExitsTwoNamingTheKey) {
  const ScratchFolder scratch("badconfig");
  const fs::path& out = scratch.path();
  std::ofstream(out / "bad.toml") << "[processing]\nworkers = 0\n";
  const pid_t pid = spawn(
      {"scan", "--config", (out / "bad.toml").string(), "--out", out.string(), "--frames", "3"},
      out);
  EXPECT_EQ(wait_exit(pid), 2);
  EXPECT_NE(read_text(out / "stderr.txt").find("processing.workers"), std::string::npos)
      << read_text(out / "stderr.txt");
}

/// Runs a shell command, returning its exit code and combined output.
int shell(const std::string& command, std::string& output) {
  output.clear();
  FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
  if (pipe == nullptr) return -1;
  std::array<char, 4096> buffer{};
  while (std::fgets(buffer.data(), buffer.size(), pipe)) output += buffer.data();
  const int status = ::pclose(pipe);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST(SessionReport, LoadsInHeadlessChromiumWithoutConsoleErrors) {
  std::string output;
  std::string browser;
  for (const char* candidate : {"chromium", "chromium-browser"})
    if (shell(std::string("command -v ") + candidate, output) == 0) browser = candidate;
  if (browser.empty()) {
    std::cerr << "skipped: Debian's chromium is not installed (tools/install-deps installs it)\n";
    std::exit(77);
  }
  const ScratchFolder scratch("chromium");
  const fs::path& out = scratch.path();
  const pid_t pid = spawn({"demo", "--frames", "40", "--out", out.string(), "--no-progress"}, out);
  ASSERT_EQ(wait_exit(pid), 0) << read_text(out / "stderr.txt");
  const fs::path report = only_session(out) / "report.html";
  ASSERT_TRUE(fs::exists(report));
  const fs::path shot = out / "report.png";
  const std::string profile = (out / "profile").string();
  const int code = shell("timeout 120 " + browser +
                             " --headless --no-sandbox --disable-gpu --disable-dev-shm-usage"
                             " --no-first-run --user-data-dir=" +
                             profile +
                             " --enable-logging=stderr --v=0 --window-size=1280,2400"
                             " --screenshot=" +
                             shot.string() + " file://" + report.string(),
                         output);
  if (code != 0 && !fs::exists(shot)) {
    std::cerr << "skipped: chromium could not start here (exit " << code << "):\n" << output;
    std::exit(77);
  }
  // Console messages appear as "CONSOLE(line)" log entries; the page has no script,
  // so any is an error (a broken image, a bad data URI).
  EXPECT_EQ(output.find(":CONSOLE("), std::string::npos) << output;
  EXPECT_EQ(output.find("Uncaught"), std::string::npos) << output;
  ASSERT_TRUE(fs::exists(shot)) << output;
  EXPECT_GT(fs::file_size(shot), 10'000u);  // a real picture of the page, not a blank
  // Every picture is embedded: the page names no file, only data URIs.
  const std::string html = read_text(report);
  EXPECT_EQ(html.find("src=\"http"), std::string::npos);
  EXPECT_EQ(html.find("src=\"file"), std::string::npos);
  EXPECT_NE(html.find("data:image/png;base64,"), std::string::npos);
  std::cout << "screenshot: " << shot << "\n";
}

}  // namespace
}  // namespace flutterscan::session
