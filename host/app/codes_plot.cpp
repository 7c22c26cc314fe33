// `flutterscan codes plot CODE... -o FILE.png`: power spectra against relative
// frequency, several codes overlaid (like the seed's figures 2, 7 and 8).

#include <cmath>
#include <iostream>
#include <memory>

#include "app/cli_errors.hpp"
#include "app/code_arguments.hpp"
#include "app/commands.hpp"
#include "codes/code_report.hpp"
#include "codes/library.hpp"
#include "codes/spectrum.hpp"
#include "plot/line_chart.hpp"

namespace flutterscan::app {
namespace {

struct PlotOptions {
  std::vector<std::string> codes;
  std::string output;
  int leds = 0;
  bool joint = false;
  bool seed_grid = false;
  int points = 2048;
  MeritFlags merit_flags;
};

constexpr plot::Rgb kLedColours[] = {
    {0.85, 0.1, 0.1}, {0.1, 0.6, 0.15}, {0.1, 0.25, 0.85}, {0.4, 0.4, 0.4}};
constexpr plot::Rgb kCodeColours[] = {{0.1, 0.1, 0.1},  {0.85, 0.1, 0.1}, {0.1, 0.25, 0.85},
                                      {0.1, 0.6, 0.15}, {0.8, 0.45, 0.0}, {0.55, 0.2, 0.7}};

std::string short_name(const std::string& argument, const LedCode& code) {
  if (codes::find_library_code(argument)) return argument;
  const std::string digits = codes::format_code(code);
  return digits.size() > 14 ? digits.substr(0, 12) + "..." : digits;
}

plot::Rgb darker(plot::Rgb colour, int step) {
  const double f = std::pow(0.6, step);
  return {colour.r * f, colour.g * f, colour.b * f};
}

void run(const PlotOptions& options) {
  const auto settings = merit_settings(options.merit_flags);
  std::vector<LedCode> codes;
  bool all_single = true;
  for (const auto& argument : options.codes) {
    codes.push_back(parse_code_argument(argument, options.leds, false));
    all_single = all_single && codes.back().leds() == 1;
  }
  plot::LineChart chart;
  chart.x_label = "relative frequency (cycles per slot)";
  chart.x_min = 0.0;
  chart.x_max = 0.5;
  if (options.joint) {
    chart.title = "Noise-weighted joint information J(f)";
    chart.y_label = "10 log10 J  (dB of e-)";
    const auto& light = settings.light;
    chart.notes.push_back("E " + std::to_string(static_cast<int>(light.electrons)) + " e-, cap " +
                          std::to_string(light.cap).substr(0, 4) + ", read noise " +
                          std::to_string(light.read_noise).substr(0, 4) +
                          " e-; higher is better, the minimum is the joint merit");
  } else {
    chart.title = "Power spectra of the codes under linear blur";
    chart.y_label = "power (dB, 20 log10 |H| / (N/2) as in the seed)";
    chart.notes.push_back("continuous spectrum (dense grid)" +
                          std::string(options.seed_grid ? "; dots: the seed's 64-point grid" : ""));
  }
  for (std::size_t i = 0; i < codes.size(); ++i) {
    const LedCode& code = codes[i];
    const std::string name = short_name(options.codes[i], code);
    const bool dashed = !all_single && i % 2 == 1;
    if (options.joint) {
      plot::Series series;
      series.label = name;
      series.colour = kCodeColours[i % std::size(kCodeColours)];
      series.line_width = 2.0;
      for (int j = 0; j < options.points; ++j) {
        const double f = 0.5 * j / (options.points - 1);
        series.x.push_back(f);
        series.y.push_back(
            10.0 * std::log10(std::max(1e-12, codes::joint_information(code, settings.light, f))));
      }
      chart.series.push_back(std::move(series));
      continue;
    }
    for (int k = 0; k < code.leds(); ++k) {
      const auto sequence = codes::led_sequence(code, k);
      const auto spectrum = codes::dense_spectrum(sequence, options.points);
      plot::Series series;
      series.label = code.leds() == 1 ? name : name + " LED " + std::to_string(k);
      series.colour = all_single ? kCodeColours[i % std::size(kCodeColours)]
                                 : darker(kLedColours[k], static_cast<int>(i / 2));
      series.dashed = dashed;
      series.x = spectrum.frequency;
      series.y = spectrum.db;
      const plot::Rgb colour = series.colour;
      chart.series.push_back(std::move(series));
      if (options.seed_grid) {
        const auto grid = codes::seed_grid_spectrum(sequence);
        plot::Series dots;
        dots.x = grid.frequency;
        dots.y = grid.db;
        dots.colour = colour;
        dots.line_width = 0;
        dots.marker_radius = 3;
        chart.series.push_back(std::move(dots));
      }
    }
  }
  if (const auto error = plot::write_png(chart, options.output); !error.empty())
    throw RuntimeFailure(error);
  std::cout << "wrote " << options.output << "\n";
}

}  // namespace

void add_codes_plot(CLI::App& codes) {
  auto options = std::make_shared<PlotOptions>();
  CLI::App* command =
      codes.add_subcommand("plot", "Chart the codes' power spectra (or J(f)) into a PNG");
  command->add_option("code", options->codes, "codes: digit strings or library names")->required();
  command->add_option("-o,--output", options->output, "PNG file to write")->required();
  command->add_option("--leds", options->leds, "LEDs in the code (default: inferred)")
      ->check(CLI::Range(1, 4));
  command->add_flag("--joint", options->joint,
                    "plot the noise-weighted joint information J(f) per code instead");
  command->add_flag("--seed-grid", options->seed_grid, "mark the seed's 64-point grid samples");
  command->add_option("--points", options->points, "samples over 0..0.5")
      ->check(CLI::Range(16, 65536))
      ->capture_default_str();
  add_merit_flags(*command, options->merit_flags);
  command->callback([options] { run(*options); });
}

}  // namespace flutterscan::app
