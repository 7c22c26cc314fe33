// Deblurring speed on a 1920x1080 RGB8 frame, frame in memory to fused grey
// latent, against the OpenCV way a user would write it (bench::OpenCvWiener,
// cv::setNumThreads(2)); and tv on a 700x250 label window on one thread (what
// a session deblurs when it restores one label's window, not the frame).
// Medians of repeated runs (Google Benchmark).

#include <benchmark/benchmark.h>

#include "bench/speed_frame.hpp"
#include "codes/library.hpp"
#include "imaging/deblur.hpp"
#include "imaging/joint_wiener.hpp"
#include "imaging/richardson_lucy.hpp"
#include "imaging/total_variation.hpp"

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
BENCHMARK_MAIN();
