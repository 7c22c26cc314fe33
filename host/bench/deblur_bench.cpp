// Deblurring speed on a 1920x1080 RGB8 frame, frame in memory to fused grey
// latent, against the OpenCV way a user would write it: per channel a 2-D
// cv::dft Wiener filter padded with cv::getOptimalDFTSize, channels averaged,
// cv::setNumThreads(2). Medians of repeated runs (Google Benchmark).

#include <benchmark/benchmark.h>

#include <opencv2/core.hpp>

#include <array>
#include <cmath>
#include <memory>
#include <random>

#include "imaging/capture_model.hpp"
#include "imaging/deblur.hpp"
#include "imaging/frame_conversion.hpp"
#include "imaging/joint_wiener.hpp"
#include "imaging/richardson_lucy.hpp"
#include "imaging/total_variation.hpp"
#include "sim/forward_model.hpp"

namespace {

using namespace flutterscan;
using imaging::Plane;

constexpr int kWidth = 1920;
constexpr int kHeight = 1080;

/// A 1080p RGB8 frame of random bars blurred by the seed's triplet, and its model.
struct Frame {
  imaging::CaptureModel model;
  cv::Mat rgb8;                       ///< interleaved RGB, 8 bits
  std::vector<imaging::ChannelPsf> psfs;
};

const Frame& frame() {
  static const Frame made = [] {
    Frame f;
    f.model.code = LedCode::parse("2212441414112412441224111241244244242212442211444144", 3).value();
    f.model.blur_px = 52;
    f.model.led_electrons = imaging::budgeted_led_electrons(f.model.code, 3000, 3);
    f.model.bit_depth = 8;
    f.model.full_well = 12000;
    f.model.gain = 12000.0 / 255.0;
    Plane scene(kWidth, kHeight, 0.35f);
    std::mt19937 rng(1);
    for (int y = 100; y < kHeight - 100; ++y)
      for (int x = 0; x < kWidth;) {
        const int run = 2 + static_cast<int>(rng() % 6);
        const float value = rng() % 2 ? 0.9f : 0.06f;
        for (int i = 0; i < run && x < kWidth; ++i) scene.at(x++, y) = value;
      }
    const auto dn = sim::record_frame(sim::expected_electrons(scene, f.model), f.model, 1);
    f.rgb8 = cv::Mat(kHeight, kWidth, CV_8UC3);
    for (int y = 0; y < kHeight; ++y)
      for (int x = 0; x < kWidth; ++x)
        for (int c = 0; c < 3; ++c) f.rgb8.at<cv::Vec3b>(y, x)[c] = static_cast<std::uint8_t>(dn.channels[static_cast<std::size_t>(c)].at(x, y));
    for (int c = 0; c < 3; ++c)
      f.psfs.push_back({imaging::channel_psf(f.model, c), imaging::channel_noise_variance(f.model, 1000)});
    return f;
  }();
  return made;
}

void JointWienerRgb8(benchmark::State& state) {
  const Frame& f = frame();
  const int threads = static_cast<int>(state.range(0));
  imaging::JointWiener wiener(f.psfs, kWidth, 1.0 / imaging::kLabelGradientVariance,
                              imaging::PlanEffort::kMeasure);
  imaging::RowPool pool(threads);
  Plane latent(kWidth, kHeight);
  // DN -> electrons for an 8-bit linear camera, deinterleaved in one pass.
  const auto gain = static_cast<float>(f.model.gain);
  const auto offset = static_cast<float>(-f.model.black_level * f.model.gain);
  const imaging::JointWiener::RowLoader load = [&f, gain, offset](int y, std::span<const std::span<float>> rows) {
    const std::uint8_t* __restrict src = f.rgb8.ptr<std::uint8_t>(y);
    float* __restrict r = rows[0].data();
    float* __restrict g = rows[1].data();
    float* __restrict b = rows[2].data();
    for (int x = 0; x < kWidth; ++x) {
      r[x] = src[3 * x] * gain + offset;
      g[x] = src[3 * x + 1] * gain + offset;
      b[x] = src[3 * x + 2] * gain + offset;
    }
  };
  for (auto _ : state) {
    wiener.deconvolve(load, kHeight, latent, pool);
    benchmark::DoNotOptimize(latent.pixels.data());
  }
  state.counters["padded_length"] = wiener.padded_length();
}

void OpenCvWiener2d(benchmark::State& state) {
  const Frame& f = frame();
  cv::setNumThreads(static_cast<int>(state.range(0)));
  const int rows = cv::getOptimalDFTSize(kHeight + 1);
  const int cols = cv::getOptimalDFTSize(kWidth + 52);
  // Each channel's PSF as a 2-D kernel, its spectrum and Wiener filter made once.
  std::array<cv::Mat, 3> filters;
  for (int c = 0; c < 3; ++c) {
    cv::Mat kernel = cv::Mat::zeros(rows, cols, CV_32F);
    const auto& taps = f.psfs[static_cast<std::size_t>(c)].taps;
    double sum = 0;
    for (double t : taps) sum += t;
    for (std::size_t j = 0; j < taps.size(); ++j) kernel.at<float>(0, static_cast<int>(j)) = static_cast<float>(taps[j] / sum);
    cv::Mat spectrum;
    cv::dft(kernel, spectrum, cv::DFT_COMPLEX_OUTPUT);
    cv::Mat planes[2];
    cv::split(spectrum, planes);
    cv::Mat power = planes[0].mul(planes[0]) + planes[1].mul(planes[1]);
    const double nsr = 0.01;
    cv::Mat denominator = power + nsr;
    cv::Mat filter_planes[2] = {planes[0] / denominator, -planes[1] / denominator};
    cv::merge(filter_planes, 2, filters[static_cast<std::size_t>(c)]);
  }
  cv::Mat channels[3], padded, spectrum, restored, sum;
  for (auto _ : state) {
    cv::split(f.rgb8, channels);
    sum = cv::Mat::zeros(kHeight, kWidth, CV_32F);
    for (int c = 0; c < 3; ++c) {
      cv::Mat as_float;
      channels[c].convertTo(as_float, CV_32F, 1.0 / 255.0);
      cv::copyMakeBorder(as_float, padded, 0, rows - kHeight, 0, cols - kWidth, cv::BORDER_REPLICATE);
      cv::dft(padded, spectrum, cv::DFT_COMPLEX_OUTPUT);
      cv::mulSpectrums(spectrum, filters[static_cast<std::size_t>(c)], spectrum, 0);
      cv::idft(spectrum, restored, cv::DFT_REAL_OUTPUT | cv::DFT_SCALE);
      sum += restored(cv::Rect(0, 0, kWidth, kHeight));
    }
    sum /= 3.0;
    benchmark::DoNotOptimize(sum.data);
  }
}

void RichardsonLucy20(benchmark::State& state) {
  const Frame& f = frame();
  imaging::Image planes;
  cv::Mat split[3];
  cv::split(f.rgb8, split);
  for (int c = 0; c < 3; ++c) {
    Plane p(kWidth, kHeight);
    for (int y = 0; y < kHeight; ++y)
      for (int x = 0; x < kWidth; ++x) p.at(x, y) = static_cast<float>(split[c].at<std::uint8_t>(y, x) * f.model.gain);
    planes.channels.push_back(std::move(p));
  }
  const imaging::RichardsonLucy rl(f.psfs, kWidth, 16.0, {20, true, 0}, imaging::PlanEffort::kMeasure);
  for (auto _ : state) {
    const Plane latent = rl.deconvolve(planes.channels, static_cast<int>(state.range(0)));
    benchmark::DoNotOptimize(latent.pixels.data());
  }
}

/// The edge-preserving joint method at its default settings, from the RGB8 frame
/// in memory: the loader, the joint Wiener warm start and every iteration are timed.
void TotalVariation(benchmark::State& state) {
  const Frame& f = frame();
  imaging::TotalVariationSettings settings;
  settings.iterations = imaging::kTotalVariationIterations;
  settings.wiener_lambda = 1.0 / imaging::kLabelGradientVariance;
  imaging::TotalVariation tv(f.psfs, kWidth, settings, imaging::PlanEffort::kMeasure);
  imaging::RowPool pool(static_cast<int>(state.range(0)));
  Plane latent(kWidth, kHeight);
  const auto gain = static_cast<float>(f.model.gain);
  const auto offset = static_cast<float>(-f.model.black_level * f.model.gain);
  const imaging::TotalVariation::RowLoader load = [&f, gain, offset](int y, std::span<const std::span<float>> rows) {
    const std::uint8_t* __restrict src = f.rgb8.ptr<std::uint8_t>(y);
    float* __restrict r = rows[0].data();
    float* __restrict g = rows[1].data();
    float* __restrict b = rows[2].data();
    for (int x = 0; x < kWidth; ++x) {
      r[x] = src[3 * x] * gain + offset;
      g[x] = src[3 * x + 1] * gain + offset;
      b[x] = src[3 * x + 2] * gain + offset;
    }
  };
  const Plane warm_start;  // empty: the joint Wiener start made inside the solver
  for (auto _ : state) {
    tv.deconvolve(load, kHeight, warm_start, latent, pool);
    benchmark::DoNotOptimize(latent.pixels.data());
  }
  state.counters["iterations"] = settings.iterations;
  state.counters["padded_length"] = tv.padded_length();
}

}  // namespace

BENCHMARK(JointWienerRgb8)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->Repetitions(5)->ReportAggregatesOnly(true)->UseRealTime();
BENCHMARK(OpenCvWiener2d)->Arg(2)->Unit(benchmark::kMillisecond)->Repetitions(5)->ReportAggregatesOnly(true)->UseRealTime();
BENCHMARK(RichardsonLucy20)->Arg(2)->Unit(benchmark::kMillisecond)->Repetitions(3)->ReportAggregatesOnly(true)->UseRealTime()->Iterations(2);
BENCHMARK(TotalVariation)->Arg(2)->Unit(benchmark::kMillisecond)->Repetitions(5)->ReportAggregatesOnly(true)->UseRealTime()->Iterations(3);
BENCHMARK_MAIN();
