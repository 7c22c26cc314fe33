// Speed against accuracy: for every method and setting, ms per 1920x1080 RGB8
// frame (2 threads, steady state) and mean PSNR per scene class at 3000 e-
// (cap 3, read noise 4 e-, 52 px blur, crosstalk, the found-joint code). One
// chart per scene class, x = ms per frame (log), y = PSNR, the Pareto front
// marked: the chart a user picks a method from.
//
//   speed_accuracy --out PREFIX [--seeds 2] [--repeats 5]
//
// Writes PREFIX-<class>.png and PREFIX.csv, prints a Markdown table.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "bench/capture_schemes.hpp"
#include "bench/speed_frame.hpp"
#include "codes/library.hpp"
#include "imaging/deblur.hpp"
#include "imaging/frame_conversion.hpp"
#include "imaging/metrics.hpp"
#include "imaging/richardson_lucy.hpp"
#include "imaging/total_variation.hpp"
#include "plot/line_chart.hpp"
#include "sim/forward_model.hpp"
#include "sim/pixel_integration.hpp"
#include "sim/scene.hpp"

namespace {

using namespace flutterscan;
using imaging::Plane;

struct Setting {
  std::string label;
  imaging::Method method;
  int iterations;  ///< rl, tv; 0 otherwise
};

struct SceneClass {
  std::string name;
  std::vector<std::string> scenes;
};

/// Steady-state ms per 1080p frame on 2 threads: plans and buffers made before timing.
double frame_ms(const bench::SpeedFrame& frame, const Setting& s, int repeats) {
  const int width = frame.rgb8.cols, height = frame.rgb8.rows;
  const auto load = bench::rgb8_row_loader(frame);
  imaging::RowPool pool(2);
  Plane latent(width, height);
  const double lambda = 1.0 / imaging::kLabelGradientVariance;
  switch (s.method) {
    case imaging::Method::kJointWiener: {
      imaging::JointWiener wiener(frame.psfs, width, lambda, imaging::PlanEffort::kMeasure);
      return bench::median_ms(repeats, [&] { wiener.deconvolve(load, height, latent, pool); });
    }
    case imaging::Method::kWienerAverage: {
      std::vector<std::unique_ptr<imaging::JointWiener>> filters;
      for (const auto& psf : frame.psfs)
        filters.push_back(std::make_unique<imaging::JointWiener>(std::span(&psf, 1), width, lambda,
                                                                 imaging::PlanEffort::kMeasure));
      std::vector<Plane> planes(3, Plane(width, height)), parts(3, Plane(width, height));
      return bench::median_ms(repeats, [&] {
        // The frame deinterleaved once, then one Wiener filter per channel, then the average.
        for (int y = 0; y < height; ++y) {
          const std::span<float> rows[3] = {planes[0].row(y), planes[1].row(y), planes[2].row(y)};
          load(y, rows);
        }
        for (std::size_t c = 0; c < 3; ++c)
          filters[c]->deconvolve(
              [&](int y, std::span<const std::span<float>> rows) {
                const auto source = planes[c].row(y);
                std::copy(source.begin(), source.end(), rows[0].begin());
              },
              height, parts[c], pool);
        for (std::size_t i = 0; i < latent.pixels.size(); ++i)
          latent.pixels[i] = (parts[0].pixels[i] + parts[1].pixels[i] + parts[2].pixels[i]) / 3.0f;
      });
    }
    case imaging::Method::kRichardsonLucy: {
      std::vector<Plane> planes(3, Plane(width, height));
      for (int y = 0; y < height; ++y) {
        const std::span<float> rows[3] = {planes[0].row(y), planes[1].row(y), planes[2].row(y)};
        load(y, rows);
      }
      imaging::RichardsonLucy rl(frame.psfs, width, 16.0, {s.iterations, true, 0},
                                 imaging::PlanEffort::kMeasure);
      return bench::median_ms(std::max(1, repeats / 2),
                              [&] { rl.deconvolve(planes, latent, pool); });
    }
    case imaging::Method::kTotalVariation: {
      imaging::TotalVariationSettings settings;
      settings.iterations = s.iterations;
      settings.wiener_lambda = lambda;
      imaging::TotalVariation tv(frame.psfs, width, settings, imaging::PlanEffort::kMeasure);
      const Plane warm_start;
      return bench::median_ms(std::max(1, repeats / 2),
                              [&] { tv.deconvolve(load, height, warm_start, latent, pool); });
    }
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::string prefix = "speed_accuracy";
  int seeds = 2, repeats = 5;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--out")
      prefix = argv[i + 1];
    else if (flag == "--seeds")
      seeds = std::stoi(argv[i + 1]);
    else if (flag == "--repeats")
      repeats = std::stoi(argv[i + 1]);
  }
  const std::vector<Setting> settings = {
      {"joint-wiener", imaging::Method::kJointWiener, 0},
      {"wiener-avg", imaging::Method::kWienerAverage, 0},
      {"rl 5", imaging::Method::kRichardsonLucy, 5},
      {"rl 10", imaging::Method::kRichardsonLucy, 10},
      {"rl 20", imaging::Method::kRichardsonLucy, 20},
      {"rl 40", imaging::Method::kRichardsonLucy, 40},
      {"tv 10", imaging::Method::kTotalVariation, 10},
      {"tv 15", imaging::Method::kTotalVariation, 15},
      {"tv 20", imaging::Method::kTotalVariation, 20},
      {"tv 40", imaging::Method::kTotalVariation, 40},
      {"tv 80", imaging::Method::kTotalVariation, 80},
  };
  const std::vector<SceneClass> classes = {
      {"1-D barcodes", {"code128:FS-0042", "ean13:4006381333931"}},
      {"2-D codes", {"qr:FLUTTERSCAN", "datamatrix:LOT-2611"}},
      {"text", {"text:LOT 42"}},
  };
  const bench::CaptureScheme scheme{"found-joint",
                                    codes::to_code(*codes::find_library_code("found-joint")), true};
  const auto model = bench::bench_camera(scheme, 3000, 3, 4, 52);
  const auto frame = bench::make_speed_frame(1920, 1080, scheme.code, 52);

  std::vector<double> ms;
  for (const auto& s : settings) {
    ms.push_back(frame_ms(frame, s, repeats));
    std::fprintf(stderr, "  %-12s %8.2f ms\n", s.label.c_str(), ms.back());
  }
  // psnr[class][setting]
  std::vector<std::vector<double>> psnr(classes.size(), std::vector<double>(settings.size(), 0.0));
  for (std::size_t k = 0; k < classes.size(); ++k) {
    int count = 0;
    for (const auto& spec_text : classes[k].scenes) {
      auto spec = sim::parse_scene(spec_text).value();
      spec.width = 640;
      spec.height = 360;
      const Plane fine = sim::render_scene(spec, sim::kSimSupersample).value();
      const Plane truth = sim::bin_pixels(fine, sim::kSimSupersample);
      const auto expected = sim::expected_electrons(fine, model, sim::kSimSupersample);
      const auto region = imaging::scored_region(truth.width, truth.height, 52, model.direction);
      for (int seed = 1; seed <= seeds; ++seed, ++count) {
        const auto electrons = imaging::dn_to_electrons(
            sim::record_frame(expected, model, static_cast<std::uint64_t>(seed)), model);
        for (std::size_t s = 0; s < settings.size(); ++s) {
          imaging::DeblurOptions options;
          options.method = settings[s].method;
          if (settings[s].iterations > 0) options.iterations = settings[s].iterations;
          psnr[k][s] += imaging::psnr(
              truth, imaging::deblur(electrons, model, options).value().latent, region);
        }
      }
    }
    for (double& p : psnr[k]) p /= count;
  }

  FILE* csv = std::fopen((prefix + ".csv").c_str(), "w");
  if (csv) std::fprintf(csv, "class,setting,ms_per_1080p_frame,psnr\n");
  std::printf("| setting | ms per 1080p frame (2 threads) |");
  for (const auto& c : classes) std::printf(" PSNR %s |", c.name.c_str());
  std::printf("\n|---|---|");
  for (std::size_t k = 0; k < classes.size(); ++k) std::printf("---|");
  std::printf("\n");
  for (std::size_t s = 0; s < settings.size(); ++s) {
    std::printf("| %s | %.1f |", settings[s].label.c_str(), ms[s]);
    for (std::size_t k = 0; k < classes.size(); ++k) {
      std::printf(" %.2f |", psnr[k][s]);
      if (csv)
        std::fprintf(csv, "%s,%s,%.3f,%.4f\n", classes[k].name.c_str(), settings[s].label.c_str(),
                     ms[s], psnr[k][s]);
    }
    std::printf("\n");
  }
  if (csv) std::fclose(csv);

  const std::map<imaging::Method, plot::Rgb> colours = {
      {imaging::Method::kJointWiener, {0.1, 0.25, 0.85}},
      {imaging::Method::kWienerAverage, {0.5, 0.5, 0.5}},
      {imaging::Method::kRichardsonLucy, {0.85, 0.1, 0.1}},
      {imaging::Method::kTotalVariation, {0.1, 0.6, 0.15}}};
  for (std::size_t k = 0; k < classes.size(); ++k) {
    plot::LineChart chart;
    chart.title = "Speed against accuracy: " + classes[k].name;
    chart.x_label = "ms per 1920x1080 RGB8 frame, 2 threads (log)";
    chart.y_label = "PSNR (dB)";
    chart.log_x = true;
    chart.notes.push_back(
        "3000 e-, cap 3, read noise 4 e-, 52 px blur, crosstalk, found-joint code; black line: "
        "Pareto front");
    for (const auto& [method, colour] : colours) {
      plot::Series points;
      points.label = imaging::method_name(method);
      points.colour = colour;
      points.line_width = 1;
      points.marker_radius = 6;
      for (std::size_t s = 0; s < settings.size(); ++s)
        if (settings[s].method == method) {
          points.x.push_back(ms[s]);
          points.y.push_back(psnr[k][s]);
        }
      chart.series.push_back(points);
    }
    // Pareto front: no other setting is both faster and more accurate.
    std::vector<std::size_t> order(settings.size());
    for (std::size_t s = 0; s < order.size(); ++s) order[s] = s;
    std::sort(order.begin(), order.end(),
              [&](std::size_t a, std::size_t b) { return ms[a] < ms[b]; });
    plot::Series front;
    front.label = "Pareto front";
    front.colour = {0, 0, 0};
    front.line_width = 2.5;
    double best = -1e9;
    for (std::size_t s : order)
      if (psnr[k][s] > best) {
        best = psnr[k][s];
        front.x.push_back(ms[s]);
        front.y.push_back(psnr[k][s]);
      }
    chart.series.push_back(front);
    std::string name = classes[k].name;
    std::replace(name.begin(), name.end(), ' ', '_');
    if (const auto error = plot::write_png(chart, prefix + "-" + name + ".png"); !error.empty()) {
      std::fprintf(stderr, "speed_accuracy: %s\n", error.c_str());
      return 1;
    }
  }
  return 0;
}
