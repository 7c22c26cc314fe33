// The datasheet's speed envelope (docs/datasheet.md; `make bench` part
// `envelope`): for each symbol and light level, the highest belt speed at which
// every one of a few hundred labels reads, for the product's coded one-of-3
// light and for a white strobe under the same light budget, each beside the
// formula that predicts it (bench/envelope_formula.hpp) and what the session's
// per-frame path cost a frame at that speed. Every label goes through the
// session's per-frame path (bench/line_labels.hpp) with the line's method
// (cascade: what a line runs; tv: tv on every frame, the ceiling) at a frame
// rate and worker count.
//
//   envelope_bench [--out DIR] [--light 60,200,600] [--labels 300] [--step-labels 20]
//                  [--mm-per-px 0.1] [--coded-slots 25,50,100,200,400]
//                  [--strobe-pulses 25,50,100,200,400,800] [--read-noise 4] [--cap 3]
//                  [--method cascade] [--fps 30] [--workers 2]
//                  [--symbols 0,1,...] [--threads 2]
//
// Writes DIR/envelope.csv (every point), DIR/envelope-code128.png and
// DIR/envelope-datamatrix.png (speed against module size, one line per light
// level and scheme) and prints the datasheet's tables as Markdown.

#include <malloc.h>
#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "bench/cpu_model.hpp"
#include "bench/envelope_formula.hpp"
#include "bench/envelope_setup.hpp"
#include "bench/line_labels.hpp"
#include "bench/speed_search.hpp"
#include "plot/line_chart.hpp"

namespace {

using namespace flutterscan;
using bench::CaptureScheme;

constexpr int kContentsPerSymbol = 16;  // distinct label contents per symbol, drawn in turn

struct Point {
  std::size_t symbol = 0;
  double light = 0;  // e-/ms
  bool coded = true;
  // results
  bench::Lighting lit;  // the slot (coded) or pulse (strobe) chosen, on its line
  bench::SpeedSearchResult measured;
  double formula = 0;  // m/s
  double seconds = 0;
  std::vector<std::pair<double, double>> tries;  // slot or pulse us, unverified speed
  std::vector<double> frame_ms;                  // each label's at the reported speed
};

/// Slot (coded light) or pulse (strobe) of `lit`, us.
double lit_us(const bench::Lighting& lit) {
  return lit.line.slot_ms * 1000 * bench::lit_run_slots(lit.scheme);
}

/// What a point's lighting is called in the tables: "coded 100 us" (its slot) or
/// "strobe 25 us" (its pulse).
std::string scheme_label(const Point& p) {
  char text[40];
  std::snprintf(text, sizeof text, "%s %g us", p.coded ? "coded" : "strobe", lit_us(p.lit));
  return text;
}

/// `values` as "25,50,100".
std::string listed(const std::vector<double>& values) {
  std::string out;
  for (double v : values) {
    char text[24];
    std::snprintf(text, sizeof text, "%s%g", out.empty() ? "" : ",", v);
    out += text;
  }
  return out;
}

/// The `q` quantile of `values` (nearest rank), 0 when there are none.
double quantile(std::vector<double> values, double q) {
  if (values.empty()) return 0;
  std::sort(values.begin(), values.end());
  const auto rank = static_cast<std::size_t>(std::ceil(q * static_cast<double>(values.size())));
  return values[std::clamp<std::size_t>(rank, 1, values.size()) - 1];
}

/// The formula: the lower of the noise limit (joint Wiener's margin) and the
/// decoder's resolution limit for the lit stretch of `scheme`.
double formula_for(const CaptureScheme& scheme, const bench::LineSetup& line, double light,
                   sim::SceneKind kind, double module, double max_speed) {
  const double noise_limit =
      bench::formula_speed([&](double v) { return bench::line_capture(scheme, line, light, v); },
                           module, 0.01, max_speed);
  const double resolution_limit =
      bench::lit_motion_speed(bench::lit_motion_modules(kind), module, line.mm_per_px,
                              bench::lit_run_slots(scheme) * line.slot_ms);
  return std::min(noise_limit, resolution_limit);
}

}  // namespace

int main(int argc, char** argv) {
  std::string out_dir = "build/bench/envelope";
  std::vector<double> light = {60, 200, 600};
  std::vector<std::size_t> symbol_pick;
  bench::LineSetup line;
  std::vector<double> coded_slots(std::begin(bench::kCodedSlotsUs), std::end(bench::kCodedSlotsUs));
  std::vector<double> strobe_pulses(std::begin(bench::kStrobePulsesUs),
                                    std::end(bench::kStrobePulsesUs));
  bench::SpeedSearchOptions search;
  bench::LineMotion motion;
  bench::LineProcessing processing;
  int threads = 2;
  double max_blur_px = 1200;
  CLI::App app{"Highest belt speed at which >= 99% of labels read, coded light and strobe"};
  app.add_option("--out", out_dir, "output directory (CSV, charts)")->capture_default_str();
  app.add_option("--light", light,
                 "light levels: e- per ms per channel, white paper, LEDs continuous")
      ->delimiter(',')
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--labels", search.final_labels, "labels that must all read at a reported speed")
      ->check(CLI::Range(0, 100000))
      ->capture_default_str();
  app.add_option("--step-labels", search.step_labels, "labels per bisection step")
      ->check(CLI::Range(1, 10000))
      ->capture_default_str();
  app.add_option("--precision", search.precision, "bisection stops at this relative width")
      ->check(CLI::Range(0.001, 1.0))
      ->capture_default_str();
  app.add_option("--mm-per-px", line.mm_per_px, "one camera pixel on the belt, mm")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--coded-slots", coded_slots,
                 "coded light's slot times searched, us (52 slots per exposure)")
      ->delimiter(',')
      ->check(CLI::Range(1.0, 10000.0))
      ->capture_default_str();
  app.add_option("--strobe-pulses", strobe_pulses,
                 "strobe pulses searched, us (longer than 100 us: whole 100-us slots)")
      ->delimiter(',')
      ->check(CLI::Range(1.0, 5200.0))
      ->capture_default_str();
  app.add_option("--read-noise", line.read_noise, "camera read noise, e- rms")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--cap", line.cap, "LED overdrive cap c")
      ->check(CLI::Range(1.0, 100.0))
      ->capture_default_str();
  app.add_option("--jitter", motion.jitter_rms, "belt jitter per slot (rms, fraction of speed)")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  app.add_option("--speed-change", motion.speed_change, "end/start speed drawn from 1 +- this")
      ->check(CLI::Range(0.0, 0.5))
      ->capture_default_str();
  app.add_option("--encoder-error", motion.encoder_error, "encoder blur drawn from 1 +- this")
      ->check(CLI::Range(0.0, 0.09))
      ->capture_default_str();
  app.add_option("--method", processing.method,
                 std::string("the session's processing.method: ") + session::kProcessingMethods)
      ->capture_default_str();
  app.add_option("--fps", processing.fps, "the line's frame rate (0: offline, every window)")
      ->check(CLI::Range(0.0, 1000.0))
      ->capture_default_str();
  app.add_option("--workers", processing.workers, "the session's processing.workers")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  app.add_option("--symbols", symbol_pick, "indices into the symbol list (default all)")
      ->delimiter(',');
  app.add_option("--max-blur", max_blur_px, "speeds stop where the exposure's blur reaches this")
      ->check(CLI::Range(10.0, 5000.0))
      ->capture_default_str();
  app.add_option("--threads", threads, "points measured at once")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    return app.exit(error) == 0 ? 0 : 2;
  }
  {
    session::ProcessingConfig check;
    if (!session::set_processing_method(processing.method, check)) {
      std::fprintf(stderr, "envelope_bench: --method %s: not one of %s\n",
                   processing.method.c_str(), session::kProcessingMethods);
      return 2;
    }
  }
  // Keep freed frames in the process, as the session does (session.cpp): every
  // label allocates and frees its frame's planes, and memory handed back to the
  // kernel returns as page faults.
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, 512 << 20);
  const auto all_symbols = bench::datasheet_symbols();
  if (symbol_pick.empty())
    for (std::size_t i = 0; i < all_symbols.size(); ++i) symbol_pick.push_back(i);
  for (std::size_t i : symbol_pick)
    if (i >= all_symbols.size()) {
      std::fprintf(stderr, "envelope_bench: no symbol %zu (0..%zu)\n", i, all_symbols.size() - 1);
      return 2;
    }
  std::error_code ec;
  std::filesystem::create_directories(out_dir, ec);
  if (ec) {
    std::fprintf(stderr, "envelope_bench: %s: %s\n", out_dir.c_str(), ec.message().c_str());
    return 1;
  }
  const auto started = std::chrono::steady_clock::now();

  // Labels, rendered once per symbol.
  std::vector<bench::LabelLine> lines;
  for (std::size_t i : symbol_pick) {
    const auto& s = all_symbols[i];
    lines.push_back(bench::LabelLine::make(s.kind, bench::module_px(s.mil, line),
                                           kContentsPerSymbol, 1000 + i));
    if (!lines.back().error().empty()) {
      std::fprintf(stderr, "envelope_bench: %s: %s\n", s.name.c_str(),
                   lines.back().error().c_str());
      return 1;
    }
  }
  // Speeds stop where the exposure's blur reaches max_blur_px.
  const auto max_speed = [&](const bench::LineSetup& on) {
    return max_blur_px * on.mm_per_px / (on.slots * on.slot_ms);
  };

  std::vector<Point> points;
  for (std::size_t s = 0; s < symbol_pick.size(); ++s)
    for (double e : light)
      for (bool coded : {true, false})
        points.push_back({s, e, coded, {line, {}}, {}, 0, 0, {}, {}});

  std::atomic<std::size_t> next{0};
  std::mutex print_mutex;
  auto worker = [&] {
    for (std::size_t i; (i = next++) < points.size();) {
      Point& p = points[i];
      const auto t0 = std::chrono::steady_clock::now();
      const auto& symbol = all_symbols[symbol_pick[p.symbol]];
      const double module = bench::module_px(symbol.mil, line);
      const bench::LabelLine& labels = lines[p.symbol];
      // Each search draws fresh label numbers: `offset` keeps them apart. The
      // final search keeps each label's frame time with its speed.
      std::vector<std::pair<double, double>> costs;  // speed, frame ms
      const auto search_scheme = [&](const CaptureScheme& scheme, const bench::LineSetup& on,
                                     std::uint64_t offset, bench::SpeedSearchOptions options,
                                     bool keep_costs) {
        options.max_speed = max_speed(on);
        options.min_speed = 0.01;
        const auto path = bench::line_path(scheme, on, p.light, processing);
        return bench::highest_reading_speed(
            [&](double v, std::uint64_t label) {
              const auto r =
                  labels.read(path, bench::exposure_blur_px(v, on), motion, offset + label);
              if (keep_costs) costs.emplace_back(v, r.frame_ms);
              return r.read;
            },
            options);
      };
      // The slot (coded) or pulse (strobe) is the line's choice: each searched
      // without verification, the fastest then searched again and verified.
      bench::SpeedSearchOptions options = search;
      double best = -1;
      std::uint64_t offset = 0;
      for (double us : p.coded ? coded_slots : strobe_pulses) {
        const auto lit =
            p.coded ? bench::coded_of_slot(line, us) : bench::strobe_of_pulse(line, us);
        const double f =
            formula_for(lit.scheme, lit.line, p.light, symbol.kind, module, max_speed(lit.line));
        p.formula = std::max(p.formula, f);
        auto quick = options;
        quick.final_labels = 0;
        quick.start = f > 0 ? f : 0.5;
        const auto r = search_scheme(lit.scheme, lit.line, offset, quick, false);
        offset += 1000000;
        p.tries.emplace_back(us, r.speed);
        if (r.speed > best) {
          best = r.speed;
          p.lit = lit;
        }
      }
      options.start = best > 0 ? best : 0.5;
      p.measured = search_scheme(p.lit.scheme, p.lit.line, offset, options, true);
      for (const auto& [v, ms] : costs)
        if (v == p.measured.speed) p.frame_ms.push_back(ms);
      p.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      const std::lock_guard lock(print_mutex);
      std::fprintf(stderr,
                   "  %-20s %5g e-/ms %-9s %6.3f m/s (formula %6.3f), frame %.1f ms (p99 %.1f), "
                   "%d labels, %.0f s\n",
                   symbol.name.c_str(), p.light, scheme_label(p).c_str(), p.measured.speed,
                   p.formula, quantile(p.frame_ms, 0.5), quantile(p.frame_ms, 0.99),
                   p.measured.labels_tried, p.seconds);
    }
  };
  {
    std::vector<std::jthread> pool;
    for (int t = 0; t < threads; ++t) pool.emplace_back(worker);
  }
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();

  // CSV.
  const std::string csv_path = out_dir + "/envelope.csv";
  FILE* csv = std::fopen(csv_path.c_str(), "w");
  if (!csv) {
    std::fprintf(stderr, "envelope_bench: cannot write %s\n", csv_path.c_str());
    return 1;
  }
  std::fprintf(csv,
               "symbol,mil,module_px,electrons_per_ms,exposure_electrons,scheme,speed_m_s,"
               "verified,labels_read,labels_tried,back_offs,at_max,formula_m_s,measured_over_"
               "formula,exposure_blur_px,lit_motion_modules,frame_ms_median,frame_ms_p99,"
               "seconds\n");
  for (const Point& p : points) {
    const auto& s = all_symbols[symbol_pick[p.symbol]];
    const double module = bench::module_px(s.mil, line);
    const double blur = bench::exposure_blur_px(p.measured.speed, p.lit.line);
    std::fprintf(
        csv, "%s,%g,%.3f,%g,%.1f,%s,%.4f,%d,%d,%d,%d,%d,%.4f,%.3f,%.2f,%.3f,%.2f,%.2f,%.1f\n",
        s.name.c_str(), s.mil, module, p.light, bench::exposure_electrons(p.light, p.lit.line),
        scheme_label(p).c_str(), p.measured.speed, p.measured.verified ? 1 : 0,
        p.measured.final_labels, p.measured.labels_tried, p.measured.back_offs,
        p.measured.at_max ? 1 : 0, p.formula, p.formula > 0 ? p.measured.speed / p.formula : 0.0,
        blur, blur * bench::lit_run_slots(p.lit.scheme) / p.lit.line.slots / module,
        quantile(p.frame_ms, 0.5), quantile(p.frame_ms, 0.99), p.seconds);
  }
  std::fclose(csv);

  // Markdown: the table, then coded over strobe.
  std::printf(
      "Optics: %.3f mm per pixel on the belt; %d slots per exposure; coded slots searched %s us, "
      "strobe pulses %s us; cap c = %g; read noise %g e-; jitter %g rms per slot, speed change "
      "+-%g%%, encoder error +-%g%%; %d labels verified per speed\n"
      "Per frame: the session's path, method %s, %g fps on %d workers; %d points at once on %s\n\n",
      line.mm_per_px, line.slots, listed(coded_slots).c_str(), listed(strobe_pulses).c_str(),
      line.cap, line.read_noise, motion.jitter_rms, 100 * motion.speed_change,
      100 * motion.encoder_error, search.final_labels, processing.method.c_str(), processing.fps,
      processing.workers, threads, bench::cpu_model().c_str());
  std::printf(
      "| symbol | module (px) | light (e-/ms) | E (e-) | scheme | measured (m/s) | "
      "formula (m/s) | measured / formula | labels read | frame ms (median, p99) |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
  for (const Point& p : points) {
    const auto& s = all_symbols[symbol_pick[p.symbol]];
    std::printf("| %s | %.2f | %g | %.0f | %s | %.2f%s | %.2f | %.2f | %d / %d%s | %.1f, %.1f |\n",
                s.name.c_str(), bench::module_px(s.mil, line), p.light,
                bench::exposure_electrons(p.light, p.lit.line), scheme_label(p).c_str(),
                p.measured.speed, p.measured.at_max ? "+" : "", p.formula,
                p.formula > 0 ? p.measured.speed / p.formula : 0.0, p.measured.final_labels,
                p.measured.verified ? p.measured.final_labels : search.final_labels,
                p.measured.verified ? "" : " (not verified)", quantile(p.frame_ms, 0.5),
                quantile(p.frame_ms, 0.99));
  }
  std::printf(
      "\n| symbol | light (e-/ms) | coded / strobe, measured | formula | coded tries (slot us: "
      "m/s, unverified) | strobe tries (pulse us: m/s, unverified) |\n|---|---|---|---|---|---|\n");
  std::vector<double> coded_over_strobe;
  for (std::size_t i = 0; i + 1 < points.size(); i += 2) {
    const Point& c = points[i];
    const Point& s = points[i + 1];
    const auto tries = [](const Point& p) {
      std::string text;
      for (const auto& [us, v] : p.tries) {
        char buf[48];
        std::snprintf(buf, sizeof buf, "%s%g: %.2f", text.empty() ? "" : ", ", us, v);
        text += buf;
      }
      return text;
    };
    // A cell with no verified speed counts as 0 m/s.
    const double coded = c.measured.verified ? c.measured.speed : 0;
    const double strobe = s.measured.verified ? s.measured.speed : 0;
    const double ratio = strobe > 0 ? coded / strobe : (coded > 0 ? 1e9 : 0);
    coded_over_strobe.push_back(ratio);
    std::printf("| %s | %g | %.2f | %.2f | %s | %s |\n",
                all_symbols[symbol_pick[c.symbol]].name.c_str(), c.light, ratio,
                s.formula > 0 ? c.formula / s.formula : 0.0, tries(c).c_str(), tries(s).c_str());
  }
  if (!coded_over_strobe.empty())
    std::printf(
        "\ncoded / strobe: median %.2f (the lower middle of %zu cells); coded faster in %td\n",
        quantile(coded_over_strobe, 0.5), coded_over_strobe.size(),
        std::count_if(coded_over_strobe.begin(), coded_over_strobe.end(),
                      [](double r) { return r > 1; }));
  // How far the formula is off: the median of measured / formula per scheme, and
  // how many points lie within 15% of the formula, as it stands and times that median.
  for (int coded = 1; coded >= 0; --coded) {
    std::vector<double> ratios;
    for (const Point& p : points)
      if (p.coded == (coded == 1) && p.formula > 0 && p.measured.speed > 0)
        ratios.push_back(p.measured.speed / p.formula);
    if (ratios.empty()) continue;
    std::sort(ratios.begin(), ratios.end());
    const double median = ratios[ratios.size() / 2];
    int within = 0, within_scaled = 0;
    for (double r : ratios) {
      within += std::abs(r - 1) <= 0.15;
      within_scaled += std::abs(r / median - 1) <= 0.15;
    }
    std::printf(
        "\n%s: measured / formula %.2f to %.2f, median %.2f; within 15%% of the formula: %d of "
        "%zu; of the formula x %.2f: %d of %zu\n",
        coded ? "coded" : "strobe", ratios.front(), ratios.back(), median, within, ratios.size(),
        median, within_scaled, ratios.size());
  }
  int total_labels = 0;
  for (const Point& p : points) total_labels += p.measured.labels_tried;
  std::printf("\n%d labels in %.0f s wall (%d threads)\n", total_labels, wall, threads);

  // Charts: speed against module size per symbology, one line per light level and scheme.
  for (const auto kind : {sim::SceneKind::kCode128, sim::SceneKind::kDataMatrix}) {
    const bool c128 = kind == sim::SceneKind::kCode128;
    plot::LineChart chart;
    chart.title = std::string("Highest belt speed with every label read: ") +
                  (c128 ? "Code 128" : "Data Matrix");
    chart.x_label = "module (mil)";
    chart.y_label = "belt speed (m/s)";
    char note[256];
    std::snprintf(note, sizeof note,
                  "%.2f mm/px, cap %g, read noise %g e-, the session's %s at %g fps; solid: coded "
                  "(best slot), dashed: strobe (best pulse)",
                  line.mm_per_px, line.cap, line.read_noise, processing.method.c_str(),
                  processing.fps);
    chart.notes.push_back(note);
    std::snprintf(note, sizeof note,
                  "every point: %d of %d labels read (a point no verification passed is left out)",
                  search.final_labels, search.final_labels);
    chart.notes.push_back(note);
    chart.y_min = 0;
    const plot::Rgb palette[] = {
        {0.85, 0.1, 0.1}, {0.1, 0.25, 0.85}, {0.1, 0.6, 0.15}, {0.8, 0.45, 0.0}, {0.55, 0.2, 0.7}};
    for (std::size_t li = 0; li < light.size(); ++li)
      for (bool coded : {true, false}) {
        plot::Series series;
        series.label = (coded ? "coded, " : "strobe, ") +
                       std::to_string(static_cast<int>(light[li])) + " e-/ms";
        series.colour = palette[li % std::size(palette)];
        series.dashed = !coded;
        series.marker_radius = 4;
        for (const Point& p : points) {
          const auto& s = all_symbols[symbol_pick[p.symbol]];
          if (s.kind != kind || p.light != light[li] || p.coded != coded) continue;
          series.x.push_back(s.mil);
          // A speed no verification passed at is not a datasheet figure: the line breaks.
          series.y.push_back(p.measured.verified ? p.measured.speed
                                                 : std::numeric_limits<double>::quiet_NaN());
        }
        if (!series.x.empty()) chart.series.push_back(std::move(series));
      }
    if (chart.series.empty()) continue;
    const std::string path =
        out_dir + (c128 ? "/envelope-code128.png" : "/envelope-datamatrix.png");
    if (const auto error = plot::write_png(chart, path); !error.empty()) {
      std::fprintf(stderr, "envelope_bench: %s\n", error.c_str());
      return 1;
    }
  }
  return 0;
}
