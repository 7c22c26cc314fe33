// session_bench: end-to-end throughput and latency of the session pipeline at
// 1920x1080 from frames already in memory (the sim camera's ring of
// pre-rendered frames), through matching, deblurring, fusion, decoding and
// results out. Rendering is measured apart. Not a test: `tools/bench`
// (BENCH_ONLY=session) runs it; docs/benchmarks.md quotes it.
//
//   session_bench [--frames N] [--width W --height H] [--csv FILE] [--stages-only]
//                 [--stage-repeats N]   (the stage table's runs, default 9; more for `perf`)
//                 [--stage-electrons E] (the stage frame's light, e-; default the sim's 3000)
//                 [--cascade]           (only the cascade against tv on every frame, dim light)
//                 [--busy RUNS]         (only a belt printed all over: RUNS runs at 60 fps, and
//                                        the same frames offline with every window decoded)
//                 [--live-view]         (only the live view's cost: live_view_runs.hpp)
//                 [--soak MINUTES]      (only memory over a long 60 fps session: soak_run.hpp)

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "bench/cpu_model.hpp"
#include "bench/live_view_runs.hpp"
#include "bench/soak_run.hpp"
#include "capture/frame_pixels.hpp"
#include "capture/sim_camera.hpp"
#include "device/controller_client.hpp"
#include "device/in_process_transport.hpp"
#include "device/virtual_controller.hpp"
#include "imaging/capture_descriptor.hpp"
#include "imaging/deblur.hpp"
#include "imaging/model_choice.hpp"
#include "imaging/model_guards.hpp"
#include "imaging/motion_frame.hpp"
#include "imaging/motion_refinement.hpp"
#include "reader/barcode_reader.hpp"
#include "reader/code_measure.hpp"
#include "reader/code_reading.hpp"
#include "reader/code_regions.hpp"
#include "reader/reader_options.hpp"
#include "session/frame_memory.hpp"
#include "session/frame_processing.hpp"
#include "session/read_record.hpp"
#include "session/session.hpp"
#include "session/worker_pool.hpp"

namespace {

using namespace flutterscan;
namespace fs = std::filesystem;

struct Run {
  std::string name;
  nlohmann::json summary;
  std::map<std::string, double> stage_ms;  ///< median per stage over processed frames
};

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

/// Medians of the per-stage times of session.jsonl's processed frames.
std::map<std::string, double> stage_medians(const fs::path& log) {
  std::map<std::string, std::vector<double>> samples;
  std::ifstream in(log);
  std::string line;
  while (std::getline(in, line)) {
    const auto j = nlohmann::json::parse(line, nullptr, false);
    if (j.is_discarded() || !j.contains("times_ms")) continue;
    for (const auto& [stage, ms] : j["times_ms"].items())
      if (stage != "deblur") samples[stage].push_back(ms.get<double>());
    if (j.contains("fit_ms"))
      for (const auto& [stage, ms] : j["fit_ms"].items())
        samples[stage].push_back(ms.get<double>());
  }
  std::map<std::string, double> out;
  for (auto& [stage, v] : samples) out[stage] = median(v);
  return out;
}

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
  // What the sim line prints, as a line's config names its symbologies (every
  // other reader ZXing has would only cost time on each window).
  c.processing.symbologies = "Code128,EAN-13,QRCode,DataMatrix";
  c.output.dir = out.string();
  c.output.timestamped_subfolder = false;
  c.output.keep_first_frames = 0;
  c.output.keep_failed_frames = false;
  c.output.report = false;
  return c;
}

/// The session `c` run to its end (its config checked first); none where the
/// config or the run fails, the error on stderr under `what`.
std::optional<session::SessionOutcome> checked_run(session::SessionConfig c,
                                                   const std::string& what) {
  if (auto problem = session::check_config(c); !problem.empty()) {
    std::cerr << "session_bench: " << problem << "\n";
    return std::nullopt;
  }
  std::atomic<bool> stop{false};
  session::SessionOutcome outcome = session::run_session(c, stop, {});
  if (!outcome.error.empty()) {
    std::cerr << "session_bench: " << what << ": " << outcome.error << "\n";
    return std::nullopt;
  }
  return outcome;
}

/// The cascade (the session's default, at 60 fps input) against tv on every
/// frame (offline, unpaced) on the same `frames` frames of a sim line at
/// `electrons` (the sim's labels: Code 128, EAN-13, QR, Data Matrix in turn):
/// object read rates side by side, drops, latency and the second passes.
int cascade_against_tv(int width, int height, int frames, const fs::path& out) {
  std::cout << "cascade (60 fps input, paced) against tv on every frame (offline), the same "
            << frames << " frames of a sim line, " << width << "x" << height << "\n\n"
            << "| e- | method | objects read | labels whole in a processed frame (sim truth), "
               "read | read rate | dropped | latency p99 ms | second passes (windows, read, over "
               "budget) | window ms p50 |\n"
            << "|---|---|---|---|---|---|---|---|---|\n";
  for (const double electrons : {300.0, 1000.0}) {
    for (const bool cascade : {true, false}) {
      fs::remove_all(out);
      session::SessionConfig c = bench_config(width, height, frames, cascade, 16667, out);
      c.camera.options.push_back({"electrons", std::to_string(electrons)});
      for (auto& [key, value] : c.camera.options)  // every frame rendered once: no object repeats
        if (key == "ring_frames") value = std::to_string(frames);
      c.optics.electrons = electrons;
      if (!cascade) {
        c.processing.cascade = false;
        c.processing.method = imaging::Method::kTotalVariation;
        c.processing.queue_depth = static_cast<std::size_t>(frames);  // offline: nothing dropped
        c.processing.refine_when_behind = true;                       // and every frame refined
      }
      const auto outcome = checked_run(c, "cascade");
      if (!outcome) return 1;
      const auto& s = outcome->summary;
      const auto truth = s.value("ground_truth", nlohmann::json::object());  // none: nothing whole
      std::cout << "| " << electrons << " | " << (cascade ? "cascade, 60 fps" : "tv, offline")
                << " | " << s["objects_read"] << " of " << s["objects"] << " | "
                << truth.value("labels_fully_in_view", 0) << ", " << truth.value("labels_read", 0)
                << " | " << s["object_read_rate"] << " | " << s["frames_dropped"] << " | "
                << s["latency_ms_p99"] << " | ";
      if (s.contains("cascade"))
        std::cout << s["cascade"]["windows_second_pass"] << ", " << s["cascade"]["windows_read"]
                  << ", " << s["cascade"]["windows_over_budget"] << " | "
                  << s["cascade"]["window_ms_p50"];
      else
        std::cout << "- | -";
      std::cout << " |\n" << std::flush;
    }
  }
  fs::remove_all(out);
  return 0;
}

/// Frames full of print: the sim line with its belt printed all over (belt=print),
/// at 60 fps input on two workers with the decode budget (`runs` runs, paced,
/// the line's config), against the same frames read offline with every window
/// decoded (unpaced, a queue that drops nothing): objects read, the labels
/// whole in a processed frame that were read, drops, latency p99, and the
/// frames the budget cut (flag decode-budget).
int busy_belt(int width, int height, int frames, int runs, const fs::path& out) {
  std::cout << "frames full of print: the sim line, belt=print, " << width << "x" << height << ", "
            << frames << " frames a run\n\n"
            << "| e- | run | objects read | labels whole in a processed frame (sim truth), read | "
               "dropped | latency p50, p99 ms | frames cut by the decode budget |\n"
            << "|---|---|---|---|---|---|---|\n";
  for (const double electrons : {300.0, 1000.0, 3000.0}) {
    for (int run = 0; run <= runs; ++run) {
      const bool offline = run == runs;
      fs::remove_all(out);
      session::SessionConfig c = bench_config(width, height, frames, !offline, 16667, out);
      c.camera.options.push_back({"electrons", std::to_string(electrons)});
      c.camera.options.push_back({"belt", "print"});
      c.camera.options.push_back({"seed", std::to_string(run + 1)});
      for (auto& [key, value] : c.camera.options)  // every frame rendered once: no object repeats
        if (key == "ring_frames") value = std::to_string(frames);
      c.optics.electrons = electrons;
      if (offline) {
        c.processing.decode_ms = session::kMaxDecodeMs;
        c.processing.queue_depth = static_cast<std::size_t>(frames);
      }
      const auto outcome = checked_run(c, "busy");
      if (!outcome) return 1;
      int cut = 0;
      std::ifstream log(out / "session.jsonl");
      for (std::string line; std::getline(log, line);) {
        const auto j = nlohmann::json::parse(line, nullptr, false);
        if (!j.is_discarded() && j.value("decode_left", 0) > 0) ++cut;
      }
      const auto& s = outcome->summary;
      const auto truth = s.value("ground_truth", nlohmann::json::object());
      std::cout << "| " << electrons << " | "
                << (offline ? std::string("offline, every window")
                            : "60 fps, " + std::to_string(run + 1))
                << " | " << s["objects_read"] << " of " << s["objects"] << " | "
                << truth.value("labels_fully_in_view", 0) << ", " << truth.value("labels_read", 0)
                << " | " << s["frames_dropped"] << " | " << s["latency_ms_p50"] << ", "
                << s["latency_ms_p99"] << " | " << cut << " |\n"
                << std::flush;
    }
  }
  fs::remove_all(out);
  return 0;
}

/// The sim conveyor of bench_config(), rendering on one thread, for the measurements apart.
capture::SimConveyorOptions one_thread_conveyor(int width, int height) {
  capture::SimConveyorOptions o;
  o.width = width;
  o.height = height;
  o.tile_width = 600;
  o.gap = 200;
  o.speed_px_per_s = 10000;
  o.counts_per_px = 2;
  o.exposure_us = 6000;
  o.render_threads = 1;
  return o;
}

double render_ms(int width, int height) {
  device::VirtualController controller;
  auto camera = capture::make_sim_camera(controller, one_thread_conveyor(width, height));
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

/// CPU time of this thread, ms: a stage's cost whatever else the machine runs.
double thread_cpu_ms() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) * 1e3 + static_cast<double>(t.tv_nsec) * 1e-6;
}

/// What one worker spends on one frame, stage by stage (medians over `repeats`
/// runs on one sim frame, thread CPU time, one thread as the bench's workers).
std::map<std::string, double> stage_costs(int width, int height, int repeats, double light_e) {
  std::map<std::string, double> out;
  auto controller = std::make_shared<device::VirtualController>();
  session::SessionConfig defaults;
  if (!session::check_config(defaults).empty()) return out;
  auto client = device::ControllerClient::connect(device::in_process_opener(controller));
  if (!client.ok()) return out;
  protocol::SetTimingRequest timing{};
  timing.slot_time_us = defaults.controller.slot_time_us;
  if (!client.value()->set_code(0, defaults.controller.parsed_code, true).ok() ||
      !client.value()->select_code(0).ok() || !client.value()->set_timing(timing).ok() ||
      !client.value()->arm().ok())
    return out;
  capture::SimConveyorOptions conveyor = one_thread_conveyor(width, height);
  if (light_e > 0) conveyor.electrons = light_e;
  auto camera = capture::make_sim_camera(*controller, conveyor);
  capture::Frame frame;
  std::string error;
  if (!camera->start().empty()) return out;
  // A frame with a whole label in view (one a deblur can read), after a few.
  for (int i = 0; i < 40 && (i < 4 || frame.truth.empty()); ++i)
    camera->next_frame(frame, std::chrono::milliseconds(1000), error);
  auto model = imaging::from_descriptor(nlohmann::json::parse(frame.descriptor_json));
  if (!model.ok()) return out;
  // The session's first pass, on one thread as the bench's workers, its plans measured first.
  session::ProcessingConfig one_thread = defaults.processing;
  one_thread.threads_per_worker = 1;
  const imaging::DeblurOptions options = session::deblur_options(one_thread);
  session::plan_row_ffts(frame.format, model.value().direction);
  std::map<std::string, std::vector<double>> samples;
  std::size_t record_bytes = 0;
  for (int r = 0; r < repeats; ++r) {
    double t = thread_cpu_ms();
    auto lap = [&](const char* stage) {
      const double now = thread_cpu_ms();
      samples[stage].push_back(now - t);
      t = now;
    };
    auto converted = capture::frame_to_electrons(frame, model.value());
    const double saturated = converted.value().saturated_share;
    const auto motion_frame =
        imaging::MotionFrame::make(std::move(converted.value().electrons), model.value().direction,
                                   converted.value().values, std::move(converted.value().levels));
    lap("convert");  // with the turn into the motion frame and its check, as the session does
    const imaging::MotionFrame& electrons = motion_frame.value();
    imaging::MotionRefinementOptions refinement;  // the session's default tolerance
    refinement.tolerance = session::ProcessingConfig{}.blur_tolerance_pct / 100;
    const auto refined = imaging::refine_motion(electrons, model.value(), refinement);
    lap("refine_motion");
    const auto choice = imaging::choose_frame_model(electrons, model.value(), false, true);
    lap("model_choice");
    auto deblurred = imaging::deblur(electrons, model.value(), options);
    lap("deblur");
    const imaging::Plane& latent = deblurred.value().latent;
    const double ratio = imaging::residual_ratio(electrons, latent, model.value(), height / 32);
    lap("guards");
    // Where to read (the session's "labels" area): the paper, and the code regions off it.
    const auto regions =
        reader::regions_to_read(reader::find_paper_runs(latent), reader::find_code_regions(latent));
    lap("regions");
    // The session's reader options; the frame moves along +x.
    const auto reading =
        reader::read_codes(latent, regions, imaging::Direction::kPlusX, reader::ReaderOptions{});
    const auto& readout = reading.readout;
    lap("decode");
    // The read record of each code read (issue 19's cost target): its measurement on the
    // latent (read_barcodes made it inside "decode" already; made again here to time it
    // alone) and its line.
    for (const reader::DecodedCode& code : readout.codes) {
      session::ObjectResult object;
      object.id = 1;
      object.value = code.text;
      object.format = code.format;
      object.best.decoded = true;
      object.best.code = code;
      object.best.code.quality = reader::measure_code(latent, code.format, code.quality.corners);
      record_bytes += session::result_line(object).size();
    }
    lap("read_record");
    if (r == 0)
      std::cout << "stage frame: blur " << model.value().blur_px << " px refined to "
                << (refined.ok() ? refined.value().blur_px : -1) << " +- "
                << (refined.ok() ? refined.value().standard_error_px : -1) << " px; model "
                << choice.describe() << ", residual ratio " << ratio << ", saturated " << saturated
                << ", " << deblurred.value().flat_rows << " of " << height << " rows flat, "
                << readout.codes.size() << " code(s) read in " << reading.windows.value_or(0)
                << " window(s)" << (readout.decoder_fault.empty() ? "" : ", decoder fault") << "\n";
  }
  for (auto& [stage, v] : samples) out[stage] = median(v);
  if (record_bytes == 0) out.erase("read_record");  // no code read: nothing to time
  return out;
}

/// The live view's cost: each input without and with it, alternating, three
/// times (medians); the live view's CPU as a share of one core: the pictures
/// it encoded per second times their CPU time, the states served and the
/// results thread's updates (at 60 fps the same share of a 16.7 ms frame budget).
int live_view_table(int width, int height, int frames, const fs::path& shared_out) {
  // A folder of this process's own: another bench running beside it must not share it.
  const fs::path out = shared_out.string() + "_live_view_" + std::to_string(::getpid());
  const auto unit = bench::live_view_update_costs();
  const double update_us = unit["update_us_per_frame"], state_us = unit["state_us"];
  std::cout << "live view, results thread: " << update_us
            << " us per frame (median); one state for the page: " << state_us << " us (median)\n\n"
            << "| input | live view | fps out | dropped | latency p50 ms | states per s | pictures "
               "per s | picture CPU ms | live view CPU, % of one core |\n"
            << "|---|---|---|---|---|---|---|---|---|\n";
  const struct {
    const char* name;
    bool paced;
    int period_us;
  } cases[] = {{"60 fps input", true, 16667}, {"30 fps input", true, 33333}};
  for (const auto& c : cases) {
    std::map<bool, std::map<std::string, std::vector<double>>> samples;
    for (int repeat = 0; repeat < 3; ++repeat)
      for (const bool live : {false, true}) {
        fs::remove_all(out);
        const auto run = bench::run_live_view_case(
            bench_config(width, height, frames, c.paced, c.period_us, out), live);
        if (!run.error.empty()) {
          std::cerr << "session_bench: " << c.name << ": " << run.error << "\n";
          return 1;
        }
        auto& m = samples[live];
        m["fps"].push_back(run.summary["fps"].get<double>());
        m["dropped"].push_back(run.summary["frames_dropped"].get<double>());
        m["p50"].push_back(run.summary["latency_ms_p50"].get<double>());
        m["states"].push_back(run.states_per_s);
        m["pictures"].push_back(run.pictures_per_s);
        m["picture_cpu"].push_back(run.picture_cpu_ms);
        const double fps = run.summary["fps"].get<double>();
        m["share"].push_back((run.encoded_per_s * run.picture_cpu_ms +
                              run.states_per_s * state_us * 1e-3 + fps * update_us * 1e-3) /
                             10);
      }
    for (const bool live : {false, true}) {
      auto& m = samples[live];
      std::cout << "| " << c.name << " | " << (live ? "on" : "off") << " | " << median(m["fps"])
                << " | " << median(m["dropped"]) << " | " << median(m["p50"]) << " | "
                << median(m["states"]) << " | " << median(m["pictures"]) << " | "
                << median(m["picture_cpu"]) << " | " << (live ? median(m["share"]) : 0.0) << " |\n";
    }
  }
  fs::remove_all(out);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  int frames = 300, width = 1920, height = 1080;
  std::string csv;
  bool stages_only = false;
  int stage_repeats = 9;
  double stage_electrons = 0;
  bool cascade_only = false;
  int busy_runs = 0;
  bool live_view = false;
  double soak_minutes = 0;
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
    else if (arg == "--stages-only")
      stages_only = true;
    else if (arg == "--stage-repeats")
      stage_repeats = std::atoi(next().c_str());
    else if (arg == "--stage-electrons")
      stage_electrons = std::atof(next().c_str());
    else if (arg == "--cascade")
      cascade_only = true;
    else if (arg == "--busy")
      busy_runs = std::atoi(next().c_str());
    else if (arg == "--live-view")
      live_view = true;
    else if (arg == "--soak")
      soak_minutes = std::atof(next().c_str());
    else {
      std::cerr << "session_bench: unknown argument '" << arg << "'\n";
      return 2;
    }
  }
  if (frames < 10 || width < 640 || height < 240 || stage_repeats < 1 || soak_minutes < 0 ||
      stage_electrons < 0) {
    std::cerr << "session_bench: --frames >= 10, --width >= 640, --height >= 240, "
                 "--stage-repeats >= 1, --soak >= 0, --stage-electrons >= 0\n";
    return 2;
  }
  // Its own folder per run: two benches at once must not remove each other's session.
  const fs::path out =
      fs::temp_directory_path() / ("flutterscan_session_bench." + std::to_string(getpid()));
  std::cout << "CPU: " << bench::cpu_model() << "\n\n";
  if (cascade_only) return cascade_against_tv(width, height, std::min(frames, 120), out);
  if (busy_runs > 0) return busy_belt(width, height, std::min(frames, 120), busy_runs, out);
  if (soak_minutes > 0) {
    const int soak_frames = static_cast<int>(soak_minutes * 60 * 60);
    auto config = bench_config(width, height, soak_frames, true, 16667, out);
    const int code = bench::soak_table(config, 5.0, csv);
    fs::remove_all(out);
    return code;
  }
  std::cout << "session pipeline, " << width << "x" << height
            << " RGB 12-bit frames from a ring of 8 pre-rendered sim frames, joint-wiener, "
               "2 workers x 1 thread, queue 4\n\n";
  const double render = render_ms(width, height);
  std::cout << "rendering (sim forward model, 1 thread, apart from the pipeline): " << render
            << " ms per frame\n\n";

  session::keep_freed_frame_memory();  // as run_session() does
  const auto costs = stage_costs(width, height, stage_repeats, stage_electrons);
  double total = 0;
  std::cout << "one worker, one frame";
  if (stage_electrons > 0) std::cout << " at " << stage_electrons << " e-";
  std::cout << ", stage by stage (thread CPU time, median of " << stage_repeats
            << "):\n\n"
               "| stage | ms |\n|---|---|\n";
  for (const char* stage :
       {"convert", "refine_motion", "model_choice", "deblur", "guards", "regions", "decode"}) {
    const auto it = costs.find(stage);
    const double ms = it == costs.end() ? 0.0 : it->second;
    total += ms;
    std::cout << "| " << stage << " | " << ms << " |\n";
  }
  std::cout << "| total | " << total << " |\n\nso at most " << 2000.0 / total
            << " fps on 2 cores (2 workers x 1 thread)\n\n";
  if (const auto it = costs.find("read_record"); it != costs.end())
    std::cout << "read record of the codes read (measurement and line; inside decode, timed "
                 "alone): "
              << it->second << " ms\n\n";
  if (stages_only) return 0;
  if (live_view) return live_view_table(width, height, frames, out);

  std::vector<Run> runs;
  // The last two keep frame files as a line does by default (the first 10, and
  // every NO-READ or D/F read); the others keep none (bench_config()).
  const struct {
    const char* name;
    bool paced;
    int period_us;
    bool keep_frames;
  } cases[] = {{"as fast as possible", false, 16667, false},
               {"30 fps input", true, 33333, false},
               {"60 fps input", true, 16667, false},
               {"30 fps input, frames kept", true, 33333, true},
               {"60 fps input, frames kept", true, 16667, true}};
  for (const auto& c : cases) {
    fs::remove_all(out);
    std::atomic<bool> stop{false};
    session::SessionConfig config = bench_config(width, height, frames, c.paced, c.period_us, out);
    if (c.keep_frames) {
      const session::OutputConfig line_default;
      config.output.keep_first_frames = line_default.keep_first_frames;
      config.output.keep_failed_frames = line_default.keep_failed_frames;
    }
    const auto outcome = session::run_session(config, stop, {});
    if (!outcome.error.empty()) {
      std::cerr << "session_bench: " << c.name << ": " << outcome.error << "\n";
      return 1;
    }
    runs.push_back(
        {c.name, outcome.summary, stage_medians(fs::path(outcome.folder) / "session.jsonl")});
  }
  std::cout << "| input | frames in | processed | dropped | seconds | fps out | latency p50 ms | "
               "p99 ms | frames saved, not saved |\n"
            << "|---|---|---|---|---|---|---|---|---|\n";
  std::ofstream table;
  if (!csv.empty()) {
    table.open(csv);
    table << "input,frames_in,processed,dropped,fps,latency_p50_ms,latency_p99_ms,render_ms\n";
  }
  for (const auto& r : runs) {
    const auto& s = r.summary;
    std::cout << "| " << r.name << " | " << s["frames_captured"] << " | " << s["frames_processed"]
              << " | " << s["frames_dropped"] << " | " << s["duration_s"] << " | " << s["fps"]
              << " | " << s["latency_ms_p50"] << " | " << s["latency_ms_p99"] << " | "
              << s["frames_saved"] << ", " << s["frames_not_saved"] << " |\n";
    if (table.is_open())
      table << '"' << r.name << "\"," << s["frames_captured"] << "," << s["frames_processed"] << ","
            << s["frames_dropped"] << "," << s["fps"] << "," << s["latency_ms_p50"] << ","
            << s["latency_ms_p99"] << "," << render << "\n";
  }
  std::cout << "\nper frame, median ms on one worker thread (model_choice: grey or colour print; "
               "guards: residual and saturation checks):\n\n| input |";
  const std::vector<std::string> stages = {
      "convert", "refine_motion", "blur_estimate", "model_choice", "deblur", "guards", "decode"};
  for (const auto& stage : stages) std::cout << " " << stage << " |";
  std::cout << "\n|---|";
  for (std::size_t i = 0; i < stages.size(); ++i) std::cout << "---|";
  std::cout << "\n";
  for (const auto& r : runs) {
    std::cout << "| " << r.name << " |";
    for (const auto& stage : stages) {
      const auto it = r.stage_ms.find(stage);
      std::cout << " " << (it == r.stage_ms.end() ? 0.0 : it->second) << " |";
    }
    std::cout << "\n";
  }
  fs::remove_all(out);
  return 0;
}
