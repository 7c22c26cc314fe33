// `flutterscan bench speed [--json] [--repeats N] [--scaling FILE.png]`:
// medians of the deblurring methods on a 1920x1080 RGB8 frame, frame in memory
// to fused grey, against the OpenCV way; optionally how the cost grows with
// frame size and blur length.
// `flutterscan bench seed --image PHOTO`: the seed's Section 6 experiment.
// `flutterscan bench stability [--out DIR] [--seeds N] [--factors a,b]`: where
// each method fails, one factor at a time (bench/stability_study.hpp).

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <iostream>
#include <memory>
#include <random>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "app/cli_errors.hpp"
#include "app/commands.hpp"
#include "bench/seed_experiment.hpp"
#include "bench/speed_frame.hpp"
#include "bench/stability_study.hpp"
#include "codes/library.hpp"
#include "imaging/deblur.hpp"
#include "imaging/joint_wiener.hpp"
#include "imaging/richardson_lucy.hpp"
#include "imaging/total_variation.hpp"
#include "plot/line_chart.hpp"

namespace flutterscan::app {
namespace {

struct SpeedOptions {
  bool json = false;
  int repeats = 15;
  std::string scaling;
};

double joint_wiener_ms(const bench::SpeedFrame& frame, int threads, int repeats) {
  imaging::JointWiener wiener(frame.psfs, frame.rgb8.cols, 1.0 / imaging::kLabelGradientVariance,
                              imaging::PlanEffort::kMeasure);
  imaging::RowPool pool(threads);
  imaging::Plane latent(frame.rgb8.cols, frame.rgb8.rows);
  const auto load = bench::rgb8_row_loader(frame);
  return bench::median_ms(repeats, [&] { wiener.deconvolve(load, frame.rgb8.rows, latent, pool); });
}

double richardson_lucy_ms(const bench::SpeedFrame& frame, int threads, int repeats) {
  std::vector<imaging::Plane> planes(3, imaging::Plane(frame.rgb8.cols, frame.rgb8.rows));
  const auto load = bench::rgb8_row_loader(frame);
  for (int y = 0; y < frame.rgb8.rows; ++y) {
    const std::span<float> rows[3] = {planes[0].row(y), planes[1].row(y), planes[2].row(y)};
    load(y, rows);
  }
  imaging::RichardsonLucy rl(frame.psfs, frame.rgb8.cols, 16.0, {20, true, 0},
                             imaging::PlanEffort::kMeasure);
  imaging::RowPool pool(threads);
  imaging::Plane latent(frame.rgb8.cols, frame.rgb8.rows);
  return bench::median_ms(repeats, [&] { rl.deconvolve(planes, latent, pool); });
}

double total_variation_ms(const bench::SpeedFrame& frame, int threads, int repeats) {
  imaging::TotalVariationSettings settings;
  settings.iterations = imaging::kTotalVariationIterations;
  settings.wiener_lambda = 1.0 / imaging::kLabelGradientVariance;
  imaging::TotalVariation tv(frame.psfs, frame.rgb8.cols, settings, imaging::PlanEffort::kMeasure);
  imaging::RowPool pool(threads);
  imaging::Plane latent(frame.rgb8.cols, frame.rgb8.rows);
  const auto load = bench::rgb8_row_loader(frame);
  const imaging::Plane warm_start;
  return bench::median_ms(repeats,
                          [&] { tv.deconvolve(load, frame.rgb8.rows, warm_start, latent, pool); });
}

/// A balanced one-of-3 code of `slots` slots (fixed seed): the cost depends on its length only.
LedCode code_of_length(int slots) {
  std::vector<std::uint8_t> masks;
  for (int t = 0; t < slots; ++t) masks.push_back(static_cast<std::uint8_t>(1U << (t % 3)));
  std::shuffle(masks.begin(), masks.end(), std::mt19937(7));
  return LedCode::from_masks(masks, 3).value();
}

/// One curve of the cost charts: a method at a thread count.
struct CostSeries {
  const char* method;
  double (*time_ms)(const bench::SpeedFrame&, int threads, int repeats);
  int threads;
  int repeats_divisor;  ///< the iterative methods take fewer timed runs
  plot::Rgb colour;
};

/// Charts `series` over frames made by `frame_at(x)` for every x; writes `path`.
void write_cost_chart(const std::string& path, const std::string& title, const std::string& x_label,
                      const std::vector<double>& xs,
                      const std::function<bench::SpeedFrame(double)>& frame_at, int repeats) {
  const std::string tv = "tv " + std::to_string(imaging::kTotalVariationIterations);
  const std::vector<CostSeries> series = {
      {"joint Wiener", joint_wiener_ms, 1, 1, {0.1, 0.25, 0.85}},
      {"joint Wiener", joint_wiener_ms, 2, 1, {0.1, 0.25, 0.85}},
      {"RL 20", richardson_lucy_ms, 1, 5, {0.85, 0.1, 0.1}},
      {"RL 20", richardson_lucy_ms, 2, 5, {0.85, 0.1, 0.1}},
      {tv.c_str(), total_variation_ms, 1, 5, {0.1, 0.6, 0.15}},
      {tv.c_str(), total_variation_ms, 2, 5, {0.1, 0.6, 0.15}},
  };
  plot::LineChart chart;
  chart.title = title;
  chart.x_label = x_label;
  chart.y_label = "ms per frame (median)";
  chart.log_x = true;
  chart.notes.push_back("seed max-min code family; dashed: 1 thread, solid: 2 threads");
  for (const auto& s : series) {
    const std::string threads = s.threads == 1 ? ", 1 thread" : ", 2 threads";
    chart.series.push_back({s.method + threads, {}, {}, s.colour, 2, s.threads == 1, 4});
  }
  for (double x : xs) {
    const auto frame = frame_at(x);
    for (std::size_t i = 0; i < series.size(); ++i) {
      const auto& s = series[i];
      chart.series[i].x.push_back(x);
      chart.series[i].y.push_back(
          s.time_ms(frame, s.threads, std::max(1, repeats / s.repeats_divisor)));
      std::fprintf(stderr, "  %g: %s %.2f ms\n", x, chart.series[i].label.c_str(),
                   chart.series[i].y.back());
    }
  }
  if (auto error = plot::write_png(chart, path); !error.empty()) throw RuntimeFailure(error);
}

void write_scaling_charts(const std::string& path, int repeats) {
  const LedCode code = codes::to_code(*codes::find_library_code("seed-maxmin-1"));
  write_cost_chart(
      path, "Time per frame against frame size (52 px blur)", "frame size (megapixels, 16:9, RGB8)",
      {0.3, 1.0, 2.07, 5.0, 12.0},
      [&](double megapixels) {
        const int height = static_cast<int>(std::sqrt(megapixels * 1e6 * 9 / 16));
        return bench::make_speed_frame(height * 16 / 9, height, code, 52);
      },
      repeats);
  write_cost_chart(
      path.substr(0, path.rfind('.')) + "-blur.png", "Time per 1080p frame against blur length",
      "blur length = code length (pixels = slots)", {13, 26, 52, 104, 208},
      [](double slots) {
        return bench::make_speed_frame(1920, 1080, code_of_length(static_cast<int>(slots)), slots);
      },
      repeats);
}

void run_speed(const SpeedOptions& options) {
  if (options.repeats < 1) throw UsageError("--repeats must be at least 1");
  const LedCode code = codes::to_code(*codes::find_library_code("seed-maxmin-1"));
  const auto frame = bench::make_speed_frame(1920, 1080, code, 52);
  nlohmann::json medians;
  medians["joint-wiener/1-thread"] = joint_wiener_ms(frame, 1, options.repeats);
  medians["joint-wiener/2-threads"] = joint_wiener_ms(frame, 2, options.repeats);
  medians["rl-20/2-threads"] = richardson_lucy_ms(frame, 2, std::max(3, options.repeats / 5));
  medians["tv-" + std::to_string(imaging::kTotalVariationIterations) + "/2-threads"] =
      total_variation_ms(frame, 2, std::max(3, options.repeats / 5));
  cv::setNumThreads(2);
  bench::OpenCvWiener baseline(frame);
  medians["opencv-dft-wiener/2-threads"] =
      bench::median_ms(options.repeats, [&] { baseline.run(frame.rgb8); });
  const double ratio = medians["opencv-dft-wiener/2-threads"].get<double>() /
                       medians["joint-wiener/2-threads"].get<double>();
  if (options.json) {
    std::cout << nlohmann::json{{"frame", "1920x1080 RGB8, 52 px blur, seed-maxmin-1"},
                                {"medians_ms", medians},
                                {"opencv_over_joint_wiener", ratio},
                                {"repeats", options.repeats}}
                     .dump()
              << "\n";
  } else {
    std::printf("1920x1080 RGB8 frame to fused grey, medians of %d runs:\n", options.repeats);
    for (const auto& [name, ms] : medians.items())
      std::printf("  %-28s %8.2f ms\n", name.c_str(), ms.get<double>());
    std::printf("  OpenCV baseline / joint Wiener (2 threads): %.1fx\n", ratio);
  }
  if (!options.scaling.empty())
    write_scaling_charts(options.scaling, std::max(3, options.repeats / 3));
}

struct SeedOptions {
  std::string image;
  std::uint64_t seed = 1;
};

void run_seed(const SeedOptions& options) {
  // As the seed's script reads it: im2double of the stored 8-bit values, per channel.
  if (!std::filesystem::exists(options.image))
    throw UsageError("--image '" + options.image + "' does not exist");
  const cv::Mat image = cv::imread(options.image, cv::IMREAD_COLOR);
  if (image.empty())
    throw UsageError("--image '" + options.image + "': cannot read it as an image");
  std::vector<imaging::Plane> photo;
  for (int c = 2; c >= 0; --c) {
    imaging::Plane plane(image.cols, image.rows);
    for (int y = 0; y < image.rows; ++y)
      for (int x = 0; x < image.cols; ++x) plane.at(x, y) = image.at<cv::Vec3b>(y, x)[c] / 255.0f;
    photo.push_back(std::move(plane));
  }
  if (image.cols <= 3 * 52)
    throw UsageError("--image must be wider than 156 pixels for a 52-pixel blur");
  std::printf(
      "| row | photo, seed noise | photo, EMVA 3000 e- | label, seed noise | label, EMVA 3000 e- "
      "|\n");
  std::printf("|---|---|---|---|---|\n");
  for (const auto& row : bench::run_seed_experiment(photo, options.seed))
    std::printf("| %s | %.2f | %.2f | %.2f | %.2f |\n", row.name.c_str(), row.photo_seed_noise,
                row.photo_emva, row.label_seed_noise, row.label_emva);
}

}  // namespace

void add_bench(CLI::App& app) {
  CLI::App* bench = app.add_subcommand("bench", "Measure speed (more in make bench)");
  bench->require_subcommand(1);
  auto options = std::make_shared<SpeedOptions>();
  CLI::App* speed =
      bench->add_subcommand("speed", "Median ms per 1080p frame per method, and the OpenCV ratio");
  speed->add_flag("--json", options->json, "print one JSON object");
  speed->add_option("--repeats", options->repeats, "timed runs per method")->capture_default_str();
  speed->add_option("--scaling", options->scaling,
                    "also chart cost against frame size and blur (PNG)");
  speed->callback([options] { run_speed(*options); });
  auto seed = std::make_shared<SeedOptions>();
  CLI::App* seed_command = bench->add_subcommand(
      "seed",
      "Rerun the seed's Section 6 experiment: PSNR per row under its noise model and EMVA's");
  seed_command
      ->add_option("--image", seed->image, "natural photograph (tools/fetch-seed-photo gets one)")
      ->required();
  seed_command->add_option("--seed", seed->seed, "noise seed")->capture_default_str();
  seed_command->callback([seed] { run_seed(*seed); });
  auto stability = std::make_shared<bench::StabilityOptions>();
  CLI::App* stability_command = bench->add_subcommand(
      "stability", "Where each method fails, one factor at a time (CSV, charts, Markdown report)");
  stability_command->add_option("--out", stability->out_dir, "directory for CSV and PNG files")
      ->capture_default_str();
  stability_command->add_option("--seeds", stability->seeds, "noise seeds per scene")
      ->check(CLI::Range(1, 100))
      ->capture_default_str();
  stability_command->add_option("--factors", stability->factors, "factors to run (default: all)")
      ->delimiter(',')
      ->check(CLI::IsMember(bench::stability_factor_names()));
  stability_command->add_option("--threads", stability->threads, "frames solved at once")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  stability_command
      ->add_option("--blur-tolerance", stability->blur_tolerance_pct,
                   "refine the motion on every frame within +-PCT% of the given blur, as the "
                   "session does (0: off)")
      ->check(CLI::Range(0.0, 99.0))
      ->capture_default_str();
  stability_command->callback([stability] {
    std::error_code error;
    std::filesystem::create_directories(stability->out_dir, error);
    if (error)
      throw RuntimeFailure("cannot create '" + stability->out_dir + "': " + error.message());
    if (const auto problem = bench::run_stability_study(*stability, stdout); !problem.empty())
      throw RuntimeFailure("bench stability: " + problem);
  });
}

}  // namespace flutterscan::app
