// Accuracy of every capture scheme and method at one light budget: PSNR, SSIM
// and barcode decode rate over a fixed scene set (several noise seeds each).
//
//   accuracy_sweep --electrons 100,300,1000,3000,10000 --caps 1,3,8 [--read-noise 4,...]
//                  [--seeds 3] [--methods joint-wiener,rl,tv] [--csv FILE]
//                  [--chart FILE.png] [--regime PREFIX] [--quiet] [--psnr-only]
//                  [--print-blur PX --texture T]   (weathered print: sim::SceneSpec)
//
// Prints one Markdown table per (E, c, read noise): mean PSNR / SSIM / decode
// rate per scheme and method (--quiet: none). --chart plots PSNR against E per
// scheme (best method, first cap and read noise). --regime writes a heat map
// per cap (PREFIX-cN.png) over light level and read noise, each cell coloured
// by the winning scheme and labelled with the best coded scheme's margin in dB
// over the best white snapshot.

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <map>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "bench/capture_schemes.hpp"
#include "imaging/deblur.hpp"
#include "imaging/frame_conversion.hpp"
#include "imaging/metrics.hpp"
#include "plot/heat_map.hpp"
#include "plot/line_chart.hpp"
#include "reader/barcode_reader.hpp"
#include "reader/code_reading.hpp"
#include "reader/reader_options.hpp"
#include "sim/forward_model.hpp"
#include "sim/pixel_integration.hpp"
#include "sim/scene.hpp"

namespace {

using namespace flutterscan;

constexpr double kBlur = 52;

struct Scene {
  std::string spec;
  std::string content;         ///< what a decoder must read; empty for text
  imaging::Plane fine;         ///< rendered sim::kSimSupersample times finer than the pixels
  imaging::Plane reflectance;  ///< the truth: what a sharp capture records
};

struct Case {
  std::size_t scheme;
  double electrons;
  double cap;
  double read_noise;
  std::size_t scene;
  int seed;
};

struct Score {
  double psnr = 0, ssim = 0;
  bool decoded = false;
};

std::vector<Scene> scenes(double print_blur, double texture) {
  const std::vector<std::pair<std::string, std::string>> specs = {
      {"code128:FS-0042", "FS-0042"},
      {"ean13:4006381333931", "4006381333931"},
      {"qr:FLUTTERSCAN", "FLUTTERSCAN"},
      {"datamatrix:LOT-2611", "LOT-2611"},
      {"text:LOT 42", ""},
  };
  std::vector<Scene> out;
  for (const auto& [spec, content] : specs) {
    auto parsed = sim::parse_scene(spec);
    parsed.value().width = 640;
    parsed.value().height = 360;
    parsed.value().module_px = 3;
    parsed.value().print_blur_px = print_blur;
    parsed.value().texture = texture;
    auto rendered = sim::render_scene(parsed.value(), sim::kSimSupersample);
    if (!rendered.ok()) {
      std::fprintf(stderr, "accuracy_sweep: %s: %s\n", spec.c_str(), rendered.error().c_str());
      std::exit(1);
    }
    const imaging::Plane truth = sim::bin_pixels(rendered.value(), sim::kSimSupersample);
    out.push_back({spec, content, std::move(rendered.value()), truth});
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<double> light = {3000};
  std::vector<double> caps = {3};
  std::vector<double> read_noises = {4};
  int seeds = 3;
  bool quiet = false;
  bool psnr_only = false;  // skip SSIM and decoding (the regime maps need PSNR alone)
  std::string regime_prefix;
  std::vector<std::string> method_names = {"joint-wiener", "rl", "tv"};
  std::string csv_path, chart_path;
  double print_blur = 0, texture = 0;
  double tv_kappa = imaging::DeblurOptions{}.tv_weight_per_noise;
  CLI::App app{"Accuracy of every capture scheme and method: PSNR, SSIM, barcode decode rate"};
  app.add_option("--electrons", light, "light levels E, e- per channel (comma-separated)")
      ->delimiter(',')
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--caps", caps, "overdrive caps c")
      ->delimiter(',')
      ->check(CLI::Range(1.0, 1000.0))
      ->capture_default_str();
  app.add_option("--read-noise", read_noises, "read noise levels, e- rms")
      ->delimiter(',')
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--seeds", seeds, "noise seeds per scene")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  app.add_option("--methods", method_names, "joint-wiener, wiener-avg, rl, tv")
      ->delimiter(',')
      ->check([](const std::string& name) {
        return imaging::method_from_name(name) ? std::string() : "unknown method '" + name + "'";
      })
      ->capture_default_str();
  app.add_option("--csv", csv_path, "write every frame's scores here");
  app.add_option("--chart", chart_path, "PNG of PSNR against light level per scheme");
  app.add_option("--regime", regime_prefix, "write regime maps PREFIX-cN.png");
  app.add_option("--print-blur", print_blur, "weathered print: ink spread, px")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--texture", texture, "weathered print: paper and toner texture (0..1)")
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--tv-kappa", tv_kappa, "tv: prior weight per unit of noise (kappa)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_flag("--quiet", quiet, "no Markdown tables");
  app.add_flag("--psnr-only", psnr_only, "skip SSIM and decoding");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    return app.exit(error) == 0 ? 0 : 2;  // --help: 0; bad usage: 2, as every command
  }
  std::vector<imaging::Method> methods;
  std::vector<std::string> used_names;
  for (const auto& name : method_names) {
    methods.push_back(*imaging::method_from_name(name));
    used_names.push_back(name);
  }
  const auto schemes = bench::standard_schemes();
  const auto scene_set = scenes(print_blur, texture);

  std::vector<Case> cases;
  for (double c : caps)
    for (double r : read_noises)
      for (double e : light)
        for (std::size_t s = 0; s < schemes.size(); ++s)
          for (std::size_t sc = 0; sc < scene_set.size(); ++sc)
            for (int seed = 1; seed <= seeds; ++seed) cases.push_back({s, e, c, r, sc, seed});

  // scores[case][method]
  std::vector<std::vector<Score>> scores(cases.size(), std::vector<Score>(methods.size()));
  std::atomic<std::size_t> next{0};
  std::mutex progress_mutex;
  std::size_t done = 0;
  auto worker = [&] {
    for (std::size_t i; (i = next++) < cases.size();) {
      const Case& k = cases[i];
      const auto model =
          bench::bench_camera(schemes[k.scheme], k.electrons, k.cap, k.read_noise, kBlur);
      const Scene& scene = scene_set[k.scene];
      const auto frame = imaging::dn_to_electrons(
          sim::record_frame(sim::expected_electrons(scene.fine, model, sim::kSimSupersample), model,
                            static_cast<std::uint64_t>(k.seed) * 7919 + k.scene),
          model);
      const auto region = imaging::scored_region(scene.reflectance.width, scene.reflectance.height,
                                                 kBlur, model.direction);
      for (std::size_t m = 0; m < methods.size(); ++m) {
        imaging::DeblurOptions options;
        options.method = methods[m];
        options.threads = 1;
        options.tv_weight_per_noise = tv_kappa;
        const auto result = imaging::deblur(frame, model, options);
        if (!result.ok()) continue;
        Score& s = scores[i][m];
        s.psnr = imaging::psnr(scene.reflectance, result.value().latent, region);
        if (psnr_only) continue;
        s.ssim = imaging::ssim(scene.reflectance, result.value().latent, region);
        if (!scene.content.empty()) {
          // The session's reader options on the whole frame (docs/benchmarks.md says so).
          const auto decoded =
              reader::code_texts(reader::read_codes(result.value().latent, {}, model.direction,
                                                    reader::whole_frame_options())
                                     .readout);
          s.decoded = std::find(decoded.begin(), decoded.end(), scene.content) != decoded.end();
        }
      }
      const std::lock_guard lock(progress_mutex);
      if (++done % 50 == 0) std::fprintf(stderr, "\r  %zu / %zu frames", done, cases.size());
    }
  };
  {
    std::vector<std::jthread> pool;
    const unsigned threads = std::max(1U, std::thread::hardware_concurrency());
    for (unsigned t = 0; t < threads; ++t) pool.emplace_back(worker);
  }
  std::fprintf(stderr, "\n");

  // Aggregate: per (cap, E, scheme, method): mean PSNR, SSIM, decode rate over barcode scenes.
  struct Sum {
    double psnr = 0, ssim = 0, barcode_psnr = 0;
    int n = 0, barcodes = 0, decoded = 0;
  };
  std::map<std::tuple<double, double, double, std::size_t, std::size_t>, Sum> sums;
  for (std::size_t i = 0; i < cases.size(); ++i)
    for (std::size_t m = 0; m < methods.size(); ++m) {
      const Case& k = cases[i];
      Sum& s = sums[{k.cap, k.read_noise, k.electrons, k.scheme, m}];
      s.psnr += scores[i][m].psnr;
      s.ssim += scores[i][m].ssim;
      ++s.n;
      if (!scene_set[k.scene].content.empty()) {
        s.barcode_psnr += scores[i][m].psnr;
        ++s.barcodes;
        s.decoded += scores[i][m].decoded;
      }
    }
  FILE* csv = csv_path.empty() ? nullptr : std::fopen(csv_path.c_str(), "w");
  if (csv)
    std::fprintf(csv,
                 "cap,electrons,read_noise,scheme,method,psnr,ssim,barcode_psnr,decode_rate\n");
  for (double c : caps)
    for (double r : read_noises)
      for (double e : light) {
        if (!quiet) {
          std::printf(
              "\n### E = %g e-, c = %g, read noise %g e-, blur %g px (%zu scenes x %d seeds)\n\n",
              e, c, r, kBlur, scene_set.size(), seeds);
          std::printf("| scheme |");
          for (const auto& name : used_names)
            std::printf(" %s PSNR / SSIM / decode |", name.c_str());
          std::printf("\n|---|");
          for (std::size_t m = 0; m < methods.size(); ++m) std::printf("---|");
          std::printf("\n");
        }
        for (std::size_t s = 0; s < schemes.size(); ++s) {
          if (!quiet) std::printf("| %s |", schemes[s].name.c_str());
          for (std::size_t m = 0; m < methods.size(); ++m) {
            const Sum& sum = sums[{c, r, e, s, m}];
            const double rate =
                sum.barcodes ? static_cast<double>(sum.decoded) / sum.barcodes : 0.0;
            if (!quiet)
              std::printf(" %.2f / %.3f / %.0f%% |", sum.psnr / sum.n, sum.ssim / sum.n,
                          100 * rate);
            if (csv)
              std::fprintf(csv, "%g,%g,%g,%s,%s,%.4f,%.4f,%.4f,%.4f\n", c, e, r,
                           schemes[s].name.c_str(), used_names[m].c_str(), sum.psnr / sum.n,
                           sum.ssim / sum.n, sum.barcodes ? sum.barcode_psnr / sum.barcodes : 0.0,
                           rate);
          }
          if (!quiet) std::printf("\n");
        }
      }
  if (csv) std::fclose(csv);

  if (!chart_path.empty() && light.size() > 1) {
    plot::LineChart chart;
    chart.title = "PSNR against light level (best method per scheme)";
    chart.x_label = "light level E (e- per channel, rect-white)";
    chart.y_label = "PSNR (dB)";
    chart.log_x = true;
    char note[160];
    std::snprintf(note, sizeof note,
                  "cap c = %g, read noise %g e-, 52 px blur, crosstalk, %zu scenes x %d seeds",
                  caps.front(), read_noises.front(), scene_set.size(), seeds);
    chart.notes.push_back(note);
    const plot::Rgb palette[] = {{0.1, 0.1, 0.1},  {0.85, 0.1, 0.1}, {0.1, 0.25, 0.85},
                                 {0.1, 0.6, 0.15}, {0.8, 0.45, 0.0}, {0.55, 0.2, 0.7},
                                 {0.0, 0.6, 0.6},  {0.6, 0.4, 0.2}};
    for (std::size_t s = 0; s < schemes.size(); ++s) {
      plot::Series series;
      series.label = schemes[s].name;
      series.colour = palette[s % std::size(palette)];
      series.dashed = s >= std::size(palette);
      series.marker_radius = 3;
      for (double e : light) {
        double best = -1e9;
        for (std::size_t m = 0; m < methods.size(); ++m) {
          const Sum& sum = sums[{caps.front(), read_noises.front(), e, s, m}];
          best = std::max(best, sum.psnr / sum.n);
        }
        series.x.push_back(e);
        series.y.push_back(best);
      }
      chart.series.push_back(std::move(series));
    }
    if (const auto error = plot::write_png(chart, chart_path); !error.empty()) {
      std::fprintf(stderr, "accuracy_sweep: %s\n", error.c_str());
      return 1;
    }
  }
  if (!regime_prefix.empty()) {
    const auto best_psnr = [&](double c, double r, double e, std::size_t s) {
      double best = -1e9;
      for (std::size_t m = 0; m < methods.size(); ++m) {
        const Sum& sum = sums[{c, r, e, s, m}];
        best = std::max(best, sum.psnr / sum.n);
      }
      return best;
    };
    for (double c : caps) {
      plot::HeatMap map;
      map.title = "Which capture scheme wins (best method each), overdrive cap " +
                  std::to_string(static_cast<int>(c));
      map.x_label = "light level E (e- per channel, rect-white)";
      map.y_label = "read noise (e- rms)";
      map.notes.push_back(
          "cell: the winner's colour; text: best coded scheme minus best white snapshot (dB)");
      for (double e : light) map.columns.push_back(std::to_string(static_cast<int>(e)));
      for (double r : read_noises) map.rows.push_back(std::to_string(static_cast<int>(r)));
      std::map<std::size_t, int> category_of;
      for (double r : read_noises)
        for (double e : light) {
          std::size_t winner = 0;
          double best_coded = -1e9, best_snapshot = -1e9;
          for (std::size_t s = 0; s < schemes.size(); ++s) {
            const double p = best_psnr(c, r, e, s);
            if (p > best_psnr(c, r, e, winner)) winner = s;
            const bool snapshot = schemes[s].name.rfind("snapshot", 0) == 0;
            (snapshot ? best_snapshot : best_coded) =
                std::max(snapshot ? best_snapshot : best_coded, p);
          }
          if (!category_of.count(winner)) {
            category_of[winner] = static_cast<int>(map.categories.size());
            map.categories.push_back(schemes[winner].name);
          }
          map.category.push_back(category_of[winner]);
          char label[32];
          std::snprintf(label, sizeof label, "%+.1f", best_coded - best_snapshot);
          map.cell_text.push_back(label);
          std::printf("regime c=%g read_noise=%g E=%g winner=%s coded_minus_snapshot=%.2f\n", c, r,
                      e, schemes[winner].name.c_str(), best_coded - best_snapshot);
        }
      const std::string path = regime_prefix + "-c" + std::to_string(static_cast<int>(c)) + ".png";
      if (const auto error = plot::write_png(map, path); !error.empty()) {
        std::fprintf(stderr, "accuracy_sweep: %s\n", error.c_str());
        return 1;
      }
    }
  }
  return 0;
}
