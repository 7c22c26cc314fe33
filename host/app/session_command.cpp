#include "app/session_command.hpp"

#include <unistd.h>

#include <atomic>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <iostream>

#include "app/cli_errors.hpp"
#include "app/live_view_option.hpp"
#include "session/session.hpp"

namespace flutterscan::app {
namespace {

std::atomic<bool> stop_requested{false};

extern "C" void on_sigint(int) {
  stop_requested = true;
  std::signal(SIGINT, SIG_DFL);  // a second Ctrl-C ends at once
}

std::string format_number(double value, int decimals) {
  char text[32];
  std::snprintf(text, sizeof text, "%.*f", decimals, value);
  return text;
}

/// " (blur-out-of-range 3, error 1)": the flags of the failed frames, counted
/// (summary.json's frames_flagged), or nothing when no frame failed.
std::string failed_flags(const nlohmann::json& summary) {
  if (summary.value("frames_failed", 0) == 0 || !summary.contains("frames_flagged")) return {};
  std::string text;
  for (const char* flag : {"blur-out-of-range", "error"})
    if (const auto n = summary["frames_flagged"].value(flag, 0); n > 0)
      text += (text.empty() ? " (" : ", ") + std::string(flag) + " " + std::to_string(n);
  return text.empty() ? text : text + ")";
}

}  // namespace

void run_session_command(session::SessionConfig config, bool progress,
                         const std::optional<std::string>& http) {
  session::LiveView live_view;
  session::LiveViewServer live_server(live_view);  // stops before live_view goes
  const bool live = start_live_view(http, live_server);
  stop_requested = false;
  std::signal(SIGINT, on_sigint);
  std::signal(SIGTERM, on_sigint);
  const bool tty = isatty(STDERR_FILENO) != 0;
  session::SessionHooks hooks;
  hooks.message = [](const std::string& text) { std::cerr << "flutterscan: " << text << "\n"; };
  hooks.listening = [](int port) {
    std::cerr << "flutterscan: results on TCP port " << port << " (one JSON line per object)\n";
  };
  if (live) hooks.live_view = &live_view;
  double last_line_s = -10;
  if (progress)
    hooks.progress = [&](const session::Progress& p) {
      if (!tty && p.elapsed_s - last_line_s < 5) return;
      last_line_s = p.elapsed_s;
      std::cerr << (tty ? "\r" : "") << "frames " << p.frames_processed << "/" << p.frames_captured
                << "  " << format_number(p.fps, 1) << " fps  drops " << p.frames_dropped
                << "  objects read " << p.objects_read << "/" << p.objects << "  "
                << format_number(p.elapsed_s, 0) << " s" << (tty ? "   " : "\n") << std::flush;
    };
  const session::SessionOutcome outcome = session::run_session(config, stop_requested, hooks);
  std::signal(SIGINT, SIG_DFL);
  std::signal(SIGTERM, SIG_DFL);
  if (progress && tty) std::cerr << "\n";
  if (!outcome.error.empty() && outcome.summary.empty()) {
    if (outcome.bad_input) throw UsageError(outcome.error);
    throw RuntimeFailure(outcome.error);
  }
  const auto& s = outcome.summary;
  std::cout << "session  " << outcome.folder << "\n"
            << "frames   " << s.value("frames_processed", 0) << " processed of "
            << s.value("frames_captured", 0) << " captured; failed " << s.value("frames_failed", 0)
            << failed_flags(s) << ", dropped " << s.value("frames_dropped", 0)
            << " (processing behind), " << s.value("camera_frames_lost", 0)
            << " lost by the camera, " << s.value("frames_without_event", 0)
            << " without exposure event, " << s.value("events_without_frame", 0)
            << " events without frame\n"
            << "objects  " << s.value("objects_read", 0) << " of " << s.value("objects", 0)
            << " read (" << format_number(100 * s.value("object_read_rate", 0.0), 1)
            << "%), mean decode rate per object "
            << format_number(100 * s.value("mean_decode_rate_per_object", 0.0), 1) << "%\n"
            << "speed    " << format_number(s.value("fps", 0.0), 1) << " fps; latency p50 "
            << format_number(s.value("latency_ms_p50", 0.0), 1) << " ms, p99 "
            << format_number(s.value("latency_ms_p99", 0.0), 1) << " ms\n"
            << "capacity " << format_number(s.value("capacity_fps", 0.0), 1) << " fps ("
            << config.processing.workers << " workers, "
            << format_number(s.value("frame_stage_ms_mean", 0.0), 1) << " ms of stages a frame)";
  if (s.contains("camera_making_ms_mean"))
    std::cout << "; the simulated camera renders a frame in "
              << format_number(s["camera_making_ms_mean"].get<double>(), 1)
              << " ms on the same cores";
  std::cout << "\n";
  if (s.contains("cascade")) {
    const auto& c = s["cascade"];
    std::cout << "cascade  " << c.value("windows_second_pass", 0)
              << " label windows joint Wiener read nothing in were deblurred again by tv; "
              << c.value("windows_read", 0) << " of them read " << c.value("codes_read", 0)
              << " code(s)";
    if (const auto over = c.value("windows_over_budget", 0); over > 0)
      std::cout << "; " << over << " left for lack of CPU time";
    std::cout << "\n";
  }
  if (s.contains("ground_truth"))
    std::cout << "truth    " << s["ground_truth"].value("labels_read", 0) << " of "
              << s["ground_truth"].value("labels_fully_in_view", 0)
              << " labels seen whole were read; wrong values: "
              << s["ground_truth"]["wrong_values"].size() << "\n";
  std::cout << "stopped  " << s.value("stopped_by", std::string()) << "\n";
  const std::string report = (std::filesystem::path(outcome.folder) / "report.html").string();
  if (std::filesystem::exists(report)) std::cout << "report   " << report << "\n";
  if (!outcome.error.empty()) throw RuntimeFailure(outcome.error);
}

}  // namespace flutterscan::app
