// Deblurring speed on a 1920x1080 RGB8 frame, frame in memory to fused grey
// latent, against the OpenCV way a user would write it (bench::OpenCvWiener,
// cv::setNumThreads(2)); tv on a 700x250 label window on one thread (what
// a session deblurs when it restores one label's window, not the frame); and
// the motion refinement on one thread, on the same frame at a constant speed
// and with a belt that jitters 0.2 of its speed per slot (the wandering motion
// fitted); and what the bar sums judge on a 696 x 496 label window before they
// sum (the second pass, one thread): where the bars are and their slope, and
// which rows cross them (over the columns judged, or, argument 1, every
// column, as before the twenty-sixth session). Medians of repeated runs
// (Google Benchmark).

#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "bench/speed_frame.hpp"
#include "codes/library.hpp"
#include "imaging/bar_sums.hpp"
#include "imaging/deblur.hpp"
#include "imaging/joint_wiener.hpp"
#include "imaging/motion_frame.hpp"
#include "imaging/motion_refinement.hpp"
#include "imaging/richardson_lucy.hpp"
#include "imaging/total_variation.hpp"
#include "reader/bar_pattern_fit.hpp"
#include "sim/scene.hpp"
#include "sim/speed_profile.hpp"

namespace {

using namespace flutterscan;
using imaging::Plane;

constexpr int kWidth = 1920;
constexpr int kHeight = 1080;
constexpr int kWindowWidth = 700;
constexpr int kWindowHeight = 250;

bench::SpeedFrame seed_frame(int width, int height) {
  return bench::make_speed_frame(width, height,
                                 codes::to_code(*codes::find_library_code("seed-maxmin-1")), 52);
}

const bench::SpeedFrame& frame() {
  static const bench::SpeedFrame made = seed_frame(kWidth, kHeight);
  return made;
}

const bench::SpeedFrame& window() {
  static const bench::SpeedFrame made = seed_frame(kWindowWidth, kWindowHeight);
  return made;
}

void JointWienerRgb8(benchmark::State& state) {
  const auto& f = frame();
  imaging::JointWiener wiener(f.psfs, kWidth, 1.0 / imaging::kLabelGradientVariance,
                              imaging::PlanEffort::kMeasure);
  imaging::RowPool pool(static_cast<int>(state.range(0)));
  Plane latent(kWidth, kHeight);
  const auto load = bench::rgb8_row_loader(f);
  for (auto _ : state) {
    wiener.deconvolve(load, kHeight, latent, pool);
    benchmark::DoNotOptimize(latent.pixels.data());
  }
  state.counters["padded_length"] = wiener.padded_length();
}

/// The 1080p frame with the belt jittering 0.2 of its speed per slot: every slot
/// edge off the constant-speed one (0.7 px rms).
const bench::SpeedFrame& jittered_frame() {
  static const bench::SpeedFrame made = [] {
    const auto code = codes::to_code(*codes::find_library_code("seed-maxmin-1"));
    const auto edges = sim::jittered_slot_boundaries(code.length(), 52, 0.2, 4);
    std::vector<double> offsets;
    for (int t = 1; t < code.length(); ++t)
      offsets.push_back(edges[static_cast<std::size_t>(t)] - 52.0 * t / code.length());
    return bench::make_speed_frame(kWidth, kHeight, code, 52, offsets);
  }();
  return made;
}

/// `f` in electrons, turned into the motion frame (as the session hands it on).
imaging::MotionFrame motion_frame(const bench::SpeedFrame& f) {
  imaging::Image electrons;
  electrons.channels.assign(3, Plane(kWidth, kHeight));
  std::vector<float> rows(3 * static_cast<std::size_t>(kWidth));
  const std::span<float> spans[] = {{rows.data(), static_cast<std::size_t>(kWidth)},
                                    {rows.data() + kWidth, static_cast<std::size_t>(kWidth)},
                                    {rows.data() + 2 * kWidth, static_cast<std::size_t>(kWidth)}};
  const auto load = bench::rgb8_row_loader(f);
  for (int y = 0; y < kHeight; ++y) {
    load(y, spans);
    for (int c = 0; c < 3; ++c)
      std::copy(spans[c].begin(), spans[c].end(),
                electrons.channels[static_cast<std::size_t>(c)].row(y).begin());
  }
  return imaging::MotionFrame::make(std::move(electrons), imaging::Direction::kPlusX).value();
}

/// Arg 0: constant speed; 1: the jittering belt. The refinement starts from the
/// constant-speed motion the encoder would give, 52 px, tolerance 10%.
void RefineMotion(benchmark::State& state) {
  const auto& f = state.range(0) ? jittered_frame() : frame();
  const auto electrons = motion_frame(f);
  imaging::CaptureModel encoder = f.model;
  encoder.block_offsets_px.clear();
  imaging::MotionRefinement r;
  for (auto _ : state) {
    r = imaging::refine_motion(electrons, encoder, {}).value();
    benchmark::DoNotOptimize(r.blur_px);
  }
  state.counters["wandering"] = r.wandering;
  state.counters["accelerating"] = r.accelerating;
  state.counters["residual"] = r.residual_per_sample;
  state.counters["rows"] = r.rows_used;
}

void OpenCvWiener2d(benchmark::State& state) {
  const auto& f = frame();
  cv::setNumThreads(static_cast<int>(state.range(0)));
  bench::OpenCvWiener baseline(f);
  for (auto _ : state) {
    const cv::Mat fused = baseline.run(f.rgb8);
    benchmark::DoNotOptimize(fused.data);
  }
}

std::vector<Plane> electron_planes(const bench::SpeedFrame& f) {
  std::vector<Plane> planes(3, Plane(kWidth, kHeight));
  const auto load = bench::rgb8_row_loader(f);
  for (int y = 0; y < kHeight; ++y) {
    const std::span<float> rows[3] = {planes[0].row(y), planes[1].row(y), planes[2].row(y)};
    load(y, rows);
  }
  return planes;
}

void RichardsonLucy20(benchmark::State& state) {
  const auto& f = frame();
  const auto planes = electron_planes(f);
  imaging::RichardsonLucy rl(f.psfs, kWidth, 16.0, {20, true, 0}, imaging::PlanEffort::kMeasure);
  imaging::RowPool pool(static_cast<int>(state.range(0)));
  Plane latent(kWidth, kHeight);
  for (auto _ : state) {
    rl.deconvolve(planes, latent, pool);
    benchmark::DoNotOptimize(latent.pixels.data());
  }
}

/// tv with the default settings on `f`, `state.range(0)` threads.
void run_total_variation(benchmark::State& state, const bench::SpeedFrame& f) {
  const int width = f.rgb8.cols, height = f.rgb8.rows;
  imaging::TotalVariationSettings settings;
  settings.iterations = imaging::kTotalVariationIterations;
  settings.wiener_lambda = 1.0 / imaging::kLabelGradientVariance;
  imaging::TotalVariation tv(f.psfs, width, settings, imaging::PlanEffort::kMeasure);
  imaging::RowPool pool(static_cast<int>(state.range(0)));
  Plane latent(width, height);
  const auto load = bench::rgb8_row_loader(f);
  const Plane warm_start;  // empty: the joint Wiener start made inside the solver
  // One frame untimed: the first allocates the solver's frame state (a steady
  // stream of frames of one height reuses it).
  tv.deconvolve(load, height, warm_start, latent, pool);
  for (auto _ : state) {
    tv.deconvolve(load, height, warm_start, latent, pool);
    benchmark::DoNotOptimize(latent.pixels.data());
  }
  state.counters["iterations"] = settings.iterations;
  state.counters["padded_length"] = tv.padded_length();
}

void TotalVariation(benchmark::State& state) {
  run_total_variation(state, frame());
}

void TotalVariationWindow(benchmark::State& state) {
  run_total_variation(state, window());
}

/// A second pass's label window: a code of bars 2-6 px wide (0.06 and 0.9),
/// 320 x 120 px, sloping 0.1 px per row, on paper (0.85) among lines of
/// text-like strokes.
const Plane& bar_window() {
  static const Plane made = [] {
    constexpr int kBarWidth = 696, kBarHeight = 496;
    Plane p(kBarWidth, kBarHeight, 0.85f);
    std::uint32_t state = 12345;
    auto next = [&] { return state = state * 1664525u + 1013904223u; };
    std::vector<float> pattern;
    while (pattern.size() < 400) {
      const auto run = 2 + static_cast<int>(next() >> 29) % 5;
      const float v = (next() >> 31) ? 0.9f : 0.06f;
      pattern.insert(pattern.end(), static_cast<std::size_t>(run), v);
    }
    for (int y = 180; y < 300; ++y)
      for (int x = 180; x < 500; ++x)
        p.at(x + static_cast<int>(0.1 * (y - 240)), y) = pattern[static_cast<std::size_t>(x - 180)];
    for (int line = 0; line < 3; ++line)  // text: short strokes
      for (int x = 120; x < 600; x += 7)
        for (int y = 60 + 30 * line; y < 72 + 30 * line; ++y) p.at(x + (next() >> 30), y) = 0.1f;
    return p;
  }();
  return made;
}

void BarRegionAndSlope(benchmark::State& state) {
  const Plane& p = bar_window();
  for (auto _ : state) {
    const imaging::Region box = imaging::bar_region(p);
    benchmark::DoNotOptimize(imaging::bar_slope(p, box, 24));
  }
}

void RowsAcrossBars(benchmark::State& state) {
  const Plane& p = bar_window();
  imaging::BarSlope slope = imaging::bar_slope(p, imaging::bar_region(p), 24);
  if (state.range(0) == 1) slope.judged_over = {0, 0, p.width, p.height};
  for (auto _ : state) benchmark::DoNotOptimize(imaging::rows_across_bars(p, slope, 24));
  state.counters["columns"] = slope.judged_over.x1 - slope.judged_over.x0;
}

/// A row `length` samples long across an EAN-13 (the simulator's label,
/// 2.5 px modules; noise 0.05 rms), read by fit over the whole row: the
/// second pass's last try on a window's bar sums.
void ReadEan13ByFit(benchmark::State& state) {
  auto spec = sim::parse_scene("ean13:590123412345");
  spec.value().width = static_cast<int>(state.range(0));
  spec.value().height = 160;
  spec.value().module_px = 2.5;
  spec.value().print_blur_px = 1.0;
  const auto label = sim::render_scene(spec.value());
  if (!label.ok()) {
    state.SkipWithError(label.error().c_str());
    return;
  }
  std::vector<double> row;
  std::uint32_t lcg = 99;
  for (int x = 0; x < label.value().width; ++x) {
    lcg = lcg * 1664525u + 1013904223u;
    const double uniform = (lcg >> 8) * (1.0 / 16777216.0) - 0.5;  // rms 1 / sqrt(12)
    row.push_back(label.value().at(x, 80) + 0.05 * std::sqrt(12.0) * uniform);
  }
  std::string text;
  for (auto _ : state)
    text = reader::read_ean13_by_fit(row, 0, static_cast<double>(row.size())).text;
  if (text != "5901234123457") state.SkipWithError(("read '" + text + "'").c_str());
  state.counters["samples"] = static_cast<double>(row.size());
}

}  // namespace

BENCHMARK(JointWienerRgb8)
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->Repetitions(5)
    ->ReportAggregatesOnly(true)
    ->UseRealTime();
BENCHMARK(OpenCvWiener2d)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->Repetitions(5)
    ->ReportAggregatesOnly(true)
    ->UseRealTime();
BENCHMARK(RichardsonLucy20)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->Repetitions(3)
    ->ReportAggregatesOnly(true)
    ->UseRealTime()
    ->Iterations(2);
BENCHMARK(TotalVariation)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->Repetitions(5)
    ->ReportAggregatesOnly(true)
    ->UseRealTime()
    ->Iterations(3);
BENCHMARK(TotalVariationWindow)
    ->Arg(1)
    ->Unit(benchmark::kMillisecond)
    ->Repetitions(9)
    ->ReportAggregatesOnly(true)
    ->UseRealTime()
    ->Iterations(10);
BENCHMARK(RefineMotion)
    ->Arg(0)
    ->Arg(1)
    ->Unit(benchmark::kMillisecond)
    ->Repetitions(9)
    ->ReportAggregatesOnly(true)
    ->MeasureProcessCPUTime()
    ->Iterations(5);
BENCHMARK(BarRegionAndSlope)
    ->Unit(benchmark::kMillisecond)
    ->Repetitions(9)
    ->ReportAggregatesOnly(true)
    ->UseRealTime();
BENCHMARK(RowsAcrossBars)
    ->Arg(0)
    ->Arg(1)
    ->Unit(benchmark::kMillisecond)
    ->Repetitions(9)
    ->ReportAggregatesOnly(true)
    ->UseRealTime();
BENCHMARK(ReadEan13ByFit)
    ->Arg(320)
    ->Arg(640)
    ->Arg(1280)
    ->Unit(benchmark::kMillisecond)
    ->Repetitions(5)
    ->ReportAggregatesOnly(true)
    ->UseRealTime();
BENCHMARK_MAIN();
