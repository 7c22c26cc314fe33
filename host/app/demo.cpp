// `flutterscan demo`: the whole product without hardware. The virtual
// controller (the firmware core on its sim port) lights a virtual conveyor of
// mixed labels; the full session pipeline captures, matches, deblurs, decodes
// and tracks a few hundred frames, then prints the summary and where
// report.html is.

#include <memory>

#include "app/commands.hpp"
#include "app/live_view_option.hpp"
#include "app/session_command.hpp"
#include "session/session_config.hpp"

namespace flutterscan::app {
namespace {

struct DemoOptions {
  std::string out = "flutterscan-demo";
  std::uint64_t frames = 240;
  std::optional<std::string> http;
  bool no_progress = false;
};

/// \brief The demo's session: 800x300 frames at 60 fps of virtual time, a belt
/// moving 52 px per 5.2 ms exposure, the seed's max-min triplet in 100 us slots,
/// the cascade's second pass on a fixed credit per frame.
/// The camera itself stops after `frames` exposures, so no exposure is left
/// without its frame.
session::SessionConfig demo_config(const std::string& out, std::uint64_t frames) {
  session::SessionConfig c;
  c.camera.spec = "sim";
  c.camera.options = {{"width", "800"},
                      {"height", "300"},
                      {"max_frames", std::to_string(frames)},
                      {"speed_px_per_s", "10000"},
                      {"frame_period_us", "16667"},
                      {"exposure_us", "6000"},
                      {"counts_per_px", "2"},
                      {"electrons", "3000"},
                      {"seed", "1"}};
  c.controller.spec = "sim";
  c.controller.code = "seed-maxmin-1";
  c.controller.slot_time_us = 100;
  c.optics.px_per_count = 0.5;
  c.output.dir = out;
  // The camera's clock is virtual: it stamps 60 fps whatever this host renders
  // and processes (about 6 fps on 2 cores), so a second-pass credit made from
  // its timestamps would be spent before any window. A fixed credit instead:
  // what a real 60 fps line on two workers leaves after a first pass of about
  // 10 ms at this size (16.7 ms x 2 x 0.85 - 10).
  c.processing.second_pass_ms = 18;
  return c;
}

}  // namespace

void add_demo(CLI::App& app) {
  auto o = std::make_shared<DemoOptions>();
  CLI::App* command = app.add_subcommand(
      "demo", "The whole pipeline on a virtual conveyor and controller (no hardware needed)");
  command->add_option("--out", o->out, "folder for the session folder")->capture_default_str();
  command->add_option("--frames", o->frames, "frames to run")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  add_http_option(command, o->http);
  command->add_flag("--no-progress", o->no_progress, "no progress line");
  command->callback(
      [o] { run_session_command(demo_config(o->out, o->frames), !o->no_progress, o->http); });
}

}  // namespace flutterscan::app
