// session_bench: end-to-end throughput and latency of the session pipeline at
// 1920x1080 from frames already in memory (the sim camera's ring of
// pre-rendered frames), through matching, deblurring, fusion, decoding and
// results out. Rendering is measured apart. Not a test: `tools/bench`
// (BENCH_ONLY=session) runs it; docs/benchmarks.md quotes it.
//
//   session_bench [--frames N] [--width W --height H] [--csv FILE]

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>

#include "capture/sim_camera.hpp"
#include "device/virtual_controller.hpp"
#include "session/session.hpp"

namespace {

using namespace flutterscan;
namespace fs = std::filesystem;

struct Run {
  std::string name;
  nlohmann::json summary;
};

session::SessionConfig bench_config(int width, int height, int frames, bool paced,
                                    int frame_period_us, const fs::path& out) {
  session::SessionConfig c;
  c.camera.spec = "sim";
  c.camera.options = {{"width", std::to_string(width)},
                      {"height", std::to_string(height)},
                      {"tile_width", "600"},
                      {"gap", "200"},
                      {"speed_px_per_s", "10000"},
                      {"counts_per_px", "2"},
                      {"frame_period_us", std::to_string(frame_period_us)},
                      {"exposure_us", "6000"},
                      {"ring_frames", "8"},
                      {"pace_realtime", paced ? "true" : "false"},
                      {"max_frames", std::to_string(frames)}};
  c.controller.spec = "sim";
  c.optics.px_per_count = 0.5;
  c.processing.workers = 2;
  c.processing.threads_per_worker = 1;
  c.processing.queue_depth = 4;
  c.output.dir = out.string();
  c.output.timestamped_subfolder = false;
  c.output.keep_first_frames = 0;
  c.output.keep_failed_frames = false;
  c.output.report = false;
  return c;
}

double render_ms(int width, int height) {
  device::VirtualController controller;
  capture::SimConveyorOptions o;
  o.width = width;
  o.height = height;
  o.tile_width = 600;
  o.gap = 200;
  o.render_threads = 1;
  auto camera = capture::make_sim_camera(controller, o);
  if (!camera->start().empty()) return -1;
  capture::Frame frame;
  std::string error;
  camera->next_frame(frame, std::chrono::milliseconds(1000), error);  // warm-up: label tiles
  const int n = 4;
  const auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < n; ++i) camera->next_frame(frame, std::chrono::milliseconds(1000), error);
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count() /
         n;
}

}  // namespace

int main(int argc, char** argv) {
  int frames = 300, width = 1920, height = 1080;
  std::string csv;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::cerr << "session_bench: " << arg << " needs a value\n";
        std::exit(2);
      }
      return argv[++i];
    };
    if (arg == "--frames")
      frames = std::atoi(next().c_str());
    else if (arg == "--width")
      width = std::atoi(next().c_str());
    else if (arg == "--height")
      height = std::atoi(next().c_str());
    else if (arg == "--csv")
      csv = next();
    else {
      std::cerr << "session_bench: unknown argument '" << arg << "'\n";
      return 2;
    }
  }
  if (frames < 10 || width < 640 || height < 240) {
    std::cerr << "session_bench: --frames >= 10, --width >= 640, --height >= 240\n";
    return 2;
  }
  const fs::path out = fs::temp_directory_path() / "flutterscan_session_bench";
  std::cout << "session pipeline, " << width << "x" << height
            << " RGB 12-bit frames from a ring of 8 pre-rendered sim frames, joint-wiener, "
               "2 workers x 1 thread, queue 4\n\n";
  const double render = render_ms(width, height);
  std::cout << "rendering (sim forward model, 1 thread, apart from the pipeline): " << render
            << " ms per frame\n\n";

  std::vector<Run> runs;
  const struct {
    const char* name;
    bool paced;
    int period_us;
  } cases[] = {{"as fast as possible", false, 16667},
               {"30 fps input", true, 33333},
               {"60 fps input", true, 16667}};
  for (const auto& c : cases) {
    fs::remove_all(out);
    std::atomic<bool> stop{false};
    const auto outcome = session::run_session(
        bench_config(width, height, frames, c.paced, c.period_us, out), stop, {});
    if (!outcome.error.empty()) {
      std::cerr << "session_bench: " << c.name << ": " << outcome.error << "\n";
      return 1;
    }
    runs.push_back({c.name, outcome.summary});
  }
  std::cout << "| input | frames in | processed | dropped | fps out | latency p50 ms | p99 ms |\n"
            << "|---|---|---|---|---|---|---|\n";
  std::ofstream table;
  if (!csv.empty()) {
    table.open(csv);
    table << "input,frames_in,processed,dropped,fps,latency_p50_ms,latency_p99_ms,render_ms\n";
  }
  for (const auto& r : runs) {
    const auto& s = r.summary;
    std::cout << "| " << r.name << " | " << s["frames_captured"] << " | " << s["frames_processed"]
              << " | " << s["frames_dropped"] << " | " << s["fps"] << " | " << s["latency_ms_p50"]
              << " | " << s["latency_ms_p99"] << " |\n";
    if (table.is_open())
      table << '"' << r.name << "\"," << s["frames_captured"] << "," << s["frames_processed"] << ","
            << s["frames_dropped"] << "," << s["fps"] << "," << s["latency_ms_p50"] << ","
            << s["latency_ms_p99"] << "," << render << "\n";
  }
  fs::remove_all(out);
  return 0;
}
