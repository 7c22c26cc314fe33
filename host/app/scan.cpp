// `flutterscan scan --camera v4l2:/dev/video0 --controller auto --config line3.toml --out
// sessions/` runs a conveyor session (docs/session.md) until the camera ends, a limit is reached or
// Ctrl-C.

#include <memory>
#include <optional>

#include "app/cli_errors.hpp"
#include "app/commands.hpp"
#include "app/live_view_option.hpp"
#include "app/session_command.hpp"
#include "imaging/deblur.hpp"
#include "session/session_config.hpp"

namespace flutterscan::app {
namespace {

struct ScanOptions {
  std::string config;
  std::optional<std::string> camera;
  std::optional<std::string> controller;
  std::optional<std::string> out;
  std::optional<std::string> method;
  std::optional<std::string> scheme;
  std::optional<std::uint64_t> frames;
  std::optional<double> seconds;
  std::optional<int> workers;
  std::optional<int> tcp_port;
  std::optional<std::string> serial;
  std::vector<std::string> camera_options;
  std::optional<std::string> http;
  bool no_progress = false;
};

void run(const ScanOptions& o) {
  session::SessionConfig config;
  if (!o.config.empty()) {
    auto loaded = session::load_config(o.config);
    if (!loaded.ok()) throw UsageError("--config: " + loaded.error());
    config = loaded.value();
  }
  if (o.camera) config.camera.spec = *o.camera;
  if (o.controller) config.controller.spec = *o.controller;
  if (o.out) config.output.dir = *o.out;
  if (o.method && !session::set_processing_method(*o.method, config.processing))
    throw UsageError(std::string("--method must be one of ") + session::kProcessingMethods);
  if (o.scheme) config.controller.code = *o.scheme;
  if (o.frames) config.processing.max_frames = *o.frames;
  if (o.seconds) config.processing.max_seconds = *o.seconds;
  if (o.workers) config.processing.workers = *o.workers;
  if (o.tcp_port) config.results.tcp_port = *o.tcp_port;
  if (o.serial) config.results.serial = *o.serial;
  for (const auto& option : o.camera_options) {
    const auto equals = option.find('=');
    if (equals == std::string::npos || equals == 0)
      throw UsageError("--camera-option '" + option + "' must be KEY=VALUE");
    config.camera.options.emplace_back(option.substr(0, equals), option.substr(equals + 1));
  }
  // Bad values are refused here, before any device is touched, naming the file.
  session::SessionConfig checked = config;
  if (auto problem = session::check_config(checked); !problem.empty())
    throw UsageError((o.config.empty() ? std::string("config") : "--config " + o.config) + ": " +
                     problem);
  run_session_command(config, !o.no_progress, o.http);
}

}  // namespace

void add_scan(CLI::App& app) {
  auto o = std::make_shared<ScanOptions>();
  CLI::App* command = app.add_subcommand(
      "scan", "Run a conveyor session: capture, match, deblur, decode, track, report");
  command->add_option("--config", o->config, "session configuration (TOML, docs/session.md)");
  command->add_option("--camera", o->camera,
                      "camera: v4l2:/dev/videoN, aravis:ID, files:DIR, sim, libcamera:ID "
                      "(flutterscan cameras lists them)");
  command->add_option("--controller", o->controller,
                      "LED controller: auto (the only one attached), a serial number, or sim");
  command->add_option("--out", o->out, "folder for session folders");
  command->add_option("--method", o->method, session::kProcessingMethods);
  command->add_option("--scheme", o->scheme,
                      "LED pattern: a code (digits or library name), or auto: the capture scheme "
                      "the regime map (docs/algorithms.md) says wins at the light measured on the "
                      "line before the session starts (every LED on, optics.paper_reflectance for "
                      "the brightest paper; optics.electrons is the fallback) and the calibrated "
                      "read noise and cap (docs/session.md)");
  command->add_option("--frames", o->frames, "stop after this many frames");
  command->add_option("--seconds", o->seconds, "stop after this long")->check(CLI::PositiveNumber);
  command->add_option("--workers", o->workers, "frames deblurred at once")
      ->check(CLI::Range(1, 64));
  command->add_option("--tcp-port", o->tcp_port, "results over TCP (0: any free port)")
      ->check(CLI::Range(0, 65535));
  command->add_option("--serial", o->serial, "results over this serial port too");
  command->add_option("--camera-option", o->camera_options,
                      "backend option KEY=VALUE (repeatable; e.g. the sim's speed_px_per_s)");
  add_http_option(command, o->http);
  command->add_flag("--no-progress", o->no_progress, "no progress line");
  command->callback([o] { run(*o); });
}

}  // namespace flutterscan::app
