// The real binary: Ctrl-C (SIGINT) mid-session leaves a valid, complete
// session folder; report.html loads in headless Chromium without console
// errors, and a screenshot of it is taken; bad configuration exits 2. The
// live view (--http): served while the session runs, an address asked for
// that is taken exits 2, the default one taken only warns; its page in
// headless Chromium shows the figures the session's summary reports.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>
#include <httplib.h>
#include <nlohmann/json.hpp>

#include <array>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <thread>

#include "session/live_view.hpp"
#include "session/live_view_server.hpp"
#include "session/session.hpp"
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
  EXPECT_EQ(static_cast<int>(frame_lines(lines).size()),
            summary["frames_captured"].get<int>() + summary["events_without_frame"].get<int>());
  EXPECT_EQ(static_cast<int>(object_lines(lines).size()), summary["objects"].get<int>());
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

/// Debian's chromium command; exits 77 (skipped) when it is not installed.
std::string chromium_or_skip() {
  std::string output;
  for (const char* candidate : {"chromium", "chromium-browser"})
    if (shell(std::string("command -v ") + candidate, output) == 0) return candidate;
  std::cerr << "skipped: Debian's chromium is not installed (tools/install-deps installs it)\n";
  std::exit(77);
}

/// Headless chromium's command line, before the page's options. Each run gets its own
/// profile folder: a second run on the same profile can wait on the first one's leftover
/// processes (their lock on the profile) until `timeout` kills it.
std::string headless(const std::string& browser, const fs::path& profile) {
  return "timeout 120 " + browser +
         " --headless --no-sandbox --disable-gpu --disable-dev-shm-usage"
         " --no-first-run --user-data-dir=" +
         profile.string();
}

// The demo's summary says the pipeline's own capacity (its workers at its frames'
// stage times) beside what the simulated camera cost the host to render a frame:
// the end-to-end speed is the camera's, which a newcomer must not take for the
// pipeline's.
TEST(DemoCli, TheSummarySaysThePipelinesCapacityBesideTheSimulatedCamerasCost) {
  const ScratchFolder scratch("demo_capacity");
  const fs::path& out = scratch.path();
  const pid_t pid = spawn({"demo", "--frames", "12", "--out", out.string(), "--no-progress"}, out);
  ASSERT_EQ(wait_exit(pid), 0) << read_text(out / "stderr.txt");
  const auto summary = nlohmann::json::parse(read_text(only_session(out) / "summary.json"));
  const double capacity = summary["capacity_fps"].get<double>();
  const double stage_ms = summary["frame_stage_ms_mean"].get<double>();
  const double camera_ms = summary["camera_making_ms_mean"].get<double>();
  EXPECT_GT(stage_ms, 0.0);
  EXPECT_GT(camera_ms, 0.0);
  // Two workers (the demo's) at the mean stage time, within the figures' rounding.
  EXPECT_NEAR(capacity, 2 * 1000.0 / stage_ms, 0.01 * capacity + 0.2);
  // The workers were never asked for more than they could do.
  EXPECT_GE(capacity, summary["fps"].get<double>());
  const std::string text = read_text(out / "stdout.txt");
  char expected[160];
  std::snprintf(expected, sizeof expected,
                "\ncapacity %.1f fps (2 workers, %.1f ms of stages a frame); the simulated "
                "camera renders a frame in %.1f ms on the same cores\n",
                capacity, stage_ms, camera_ms);
  EXPECT_NE(text.find(expected), std::string::npos) << expected << "\n" << text;
}

TEST(SessionReport, LoadsInHeadlessChromiumWithoutConsoleErrors) {
  std::string output;
  const std::string browser = chromium_or_skip();
  const ScratchFolder scratch("chromium");
  const fs::path& out = scratch.path();
  const pid_t pid = spawn({"demo", "--frames", "40", "--out", out.string(), "--no-progress"}, out);
  ASSERT_EQ(wait_exit(pid), 0) << read_text(out / "stderr.txt");
  const fs::path folder = only_session(out);
  const fs::path report = folder / "report.html";
  ASSERT_TRUE(fs::exists(report));
  const fs::path shot = out / "report.png";
  const int code = shell(headless(browser, out / "profile") +
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
  // The page as chromium built it starts with the verdict in words, from the summary.
  std::string dom;
  shell(headless(browser, out / "profile-dom") + " --dump-dom file://" + report.string(), dom);
  const auto summary = nlohmann::json::parse(read_text(folder / "summary.json"));
  const std::string verdict = std::to_string(summary["objects_read"].get<int>()) + " of " +
                              std::to_string(summary["objects"].get<int>()) + " objects read";
  EXPECT_NE(dom.find(verdict), std::string::npos) << dom.substr(0, 3000);
  EXPECT_LT(dom.find("id=\"verdict\""), dom.find("What went wrong, and what to do"));
  std::cout << "screenshot: " << shot << "\n";
}

/// The port of the live view the binary announced on stderr ("live view on
/// http://127.0.0.1:PORT/"), waiting up to a minute; 0 if it never did.
int announced_port(const fs::path& stderr_path) {
  const std::string announcement = "live view on http://127.0.0.1:";
  for (int i = 0; i < 600; ++i) {
    const std::string err = read_text(stderr_path);
    if (const auto at = err.find(announcement); at != std::string::npos)
      return std::atoi(err.c_str() + at + announcement.size());
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return 0;
}

TEST(LiveViewCli, TheDemoServesItsLiveViewWhileItRuns) {
  const ScratchFolder scratch("live_cli");
  const fs::path& out = scratch.path();
  const pid_t pid = spawn({"demo", "--frames", "100000", "--http", "127.0.0.1:0", "--out",
                           out.string(), "--no-progress"},
                          out);
  const int port = announced_port(out / "stderr.txt");
  ASSERT_GT(port, 0) << read_text(out / "stderr.txt");
  EXPECT_NE(read_text(out / "stderr.txt").find("(read-only)"), std::string::npos);
  EXPECT_EQ(read_text(out / "stderr.txt").find("reachable from the network"), std::string::npos);
  httplib::Client client("127.0.0.1", port);
  nlohmann::json state;
  for (int i = 0; i < 600; ++i) {
    if (auto r = client.Get("/state.json"); r && r->status == 200) {
      state = nlohmann::json::parse(r->body);
      if (state["frames"]["processed"].get<int>() >= 5) break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  ASSERT_GE(state["frames"]["processed"].get<int>(), 5) << state.dump();
  EXPECT_EQ(state["state"], "armed");
  EXPECT_EQ(state["line"]["code"], "seed-maxmin-1");
  EXPECT_EQ(fs::path(state["folder"].get<std::string>()).parent_path(), out);
  auto metrics = client.Get("/metrics");
  ASSERT_TRUE(metrics);
  EXPECT_NE(metrics->body.find("flutterscan_frames_processed_total "), std::string::npos);
  auto page = client.Get("/");
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 200);
  auto post = client.Post("/state.json", "{\"state\":\"disarmed\"}", "application/json");
  ASSERT_TRUE(post);
  EXPECT_EQ(post->status, 405);
  ASSERT_EQ(::kill(pid, SIGINT), 0);
  EXPECT_EQ(wait_exit(pid), 0) << read_text(out / "stderr.txt");
}

TEST(LiveViewCli, AnAddressAskedForThatIsTakenOrBadExitsTwoBeforeTheLine) {
  const ScratchFolder scratch("live_cli_taken");
  const fs::path& out = scratch.path();
  LiveView view;
  LiveViewServer taken(view);
  ASSERT_EQ(taken.listen({"127.0.0.1", 0}), "");
  const std::string address = "127.0.0.1:" + std::to_string(taken.port());
  const pid_t pid = spawn(
      {"demo", "--frames", "3", "--http", address, "--out", out.string(), "--no-progress"}, out);
  EXPECT_EQ(wait_exit(pid), 2);
  const std::string err = read_text(out / "stderr.txt");
  EXPECT_NE(err.find("cannot listen on " + address + ": the port is in use"), std::string::npos)
      << err;
  EXPECT_TRUE(only_session(out).empty());  // no session started
  const pid_t bad = spawn(
      {"demo", "--frames", "3", "--http", "8090", "--out", out.string(), "--no-progress"}, out);
  EXPECT_EQ(wait_exit(bad), 2);
  EXPECT_NE(read_text(out / "stderr.txt").find("--http '8090' must be ADDR:PORT"),
            std::string::npos)
      << read_text(out / "stderr.txt");
}

TEST(LiveViewCli, TheDefaultAddressTakenOnlyWarnsAndTheSessionRuns) {
  const ScratchFolder scratch("live_cli_default");
  const fs::path& out = scratch.path();
  LiveView view;
  LiveViewServer taken(view);
  if (!taken.listen({kLiveViewDefaultHost, kLiveViewDefaultPort}).empty())
    GTEST_SKIP() << "the default port is held by another process: it may let go any time";
  const pid_t pid = spawn({"demo", "--frames", "5", "--out", out.string(), "--no-progress"}, out);
  EXPECT_EQ(wait_exit(pid), 0) << read_text(out / "stderr.txt");
  EXPECT_NE(read_text(out / "stderr.txt")
                .find("warning: live view: cannot listen on 127.0.0.1:8090: the port is in use; "
                      "the session runs without it"),
            std::string::npos)
      << read_text(out / "stderr.txt");
  EXPECT_TRUE(fs::exists(only_session(out) / "summary.json"));
}

/// The text of the element with `id` in `dom` (its first text, up to the next tag).
std::string element_text(const std::string& dom, const std::string& id) {
  const std::string opening = "id=\"" + id + "\"";
  const auto at = dom.find(opening);
  if (at == std::string::npos) return "(no #" + id + ")";
  const auto start = dom.find('>', at) + 1;
  return dom.substr(start, dom.find('<', start) - start);
}

std::string percent_text(double share) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f%%", 100 * share);
  return text;
}

TEST(LiveViewPage, ShowsTheFiguresOfTheSessionInHeadlessChromium) {
  const std::string browser = chromium_or_skip();
  const ScratchFolder scratch("live_chromium");
  const fs::path& out = scratch.path();
  LiveView view;
  LiveViewServer server(view);
  ASSERT_EQ(server.listen({"127.0.0.1", 0}), "");
  SessionHooks hooks;
  hooks.live_view = &view;
  std::atomic<bool> stop{false};
  const SessionOutcome outcome =
      run_session(testing::small_sim_config(out / "session", 90), stop, hooks);
  ASSERT_EQ(outcome.error, "");
  const auto& summary = outcome.summary;
  const std::string url = "http://127.0.0.1:" + std::to_string(server.port()) + "/";
  // The DOM after 4 s of the page's (virtual) time, and chromium's log with it.
  std::string dom;
  const int code = shell(headless(browser, out / "profile-dom") +
                             " --enable-logging=stderr --v=0 --virtual-time-budget=4000"
                             " --dump-dom " +
                             url,
                         dom);
  if (code != 0 && dom.find("<html") == std::string::npos) {
    std::cerr << "skipped: chromium could not start here (exit " << code << "):\n" << dom;
    std::exit(77);
  }
  // No console message: the script ran without error, nothing was refused or missing.
  EXPECT_EQ(dom.find(":CONSOLE("), std::string::npos) << dom;
  EXPECT_EQ(dom.find("Uncaught"), std::string::npos) << dom;
  // The page updated itself from /state.json: the figures are the summary's.
  EXPECT_NE(element_text(dom, "updates"), "0") << dom;
  EXPECT_EQ(element_text(dom, "state"), "disarmed");
  EXPECT_EQ(element_text(dom, "frames-processed"), summary["frames_processed"].dump());
  EXPECT_EQ(element_text(dom, "frames-captured"), summary["frames_captured"].dump());
  EXPECT_EQ(element_text(dom, "frames-dropped"), summary["frames_dropped"].dump());
  EXPECT_EQ(element_text(dom, "objects-read"), summary["objects_read"].dump());
  EXPECT_EQ(element_text(dom, "objects"), summary["objects"].dump());
  EXPECT_EQ(element_text(dom, "read-rate"), percent_text(summary["object_read_rate"]));
  EXPECT_EQ(element_text(dom, "decode-rate"), percent_text(summary["mean_decode_rate_per_object"]));
  EXPECT_NE(element_text(dom, "picture-caption").find("code(s) read"), std::string::npos);
  EXPECT_NE(dom.find("src=\"frame/fused.jpg?frame="), std::string::npos);
  // A screenshot, kept in the test's working folder for a look: after 3 s of real time
  // (under load, chromium's virtual time with the page polling stalled past 120 s at times).
  const fs::path shot = fs::current_path() / "live_view.png";
  fs::remove(shot);
  std::string output;
  shell(headless(browser, out / "profile-screenshot") +
            " --window-size=1280,1400 --timeout=3000 --screenshot=" + shot.string() + " " + url,
        output);
  ASSERT_TRUE(fs::exists(shot)) << output;
  EXPECT_GT(fs::file_size(shot), 20'000u);  // the page with its pictures, not a blank
  std::cout << "screenshot: " << shot << "\n";
}

}  // namespace
}  // namespace flutterscan::session
