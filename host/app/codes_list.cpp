// `flutterscan codes list [--json]`: the built-in code library with merits.

#include <cstdio>
#include <iostream>
#include <memory>

#include "app/code_arguments.hpp"
#include "app/commands.hpp"
#include "codes/code_report.hpp"
#include "codes/library.hpp"

namespace flutterscan::app {
namespace {

struct ListOptions {
  bool json = false;
  MeritFlags merit_flags;
};

std::string cell(const codes::CodeReport& report, codes::Merit merit, const char* format) {
  for (const auto& entry : report.merits)
    if (entry.merit == merit && entry.value) {
      char text[32];
      std::snprintf(text, sizeof text, format, *entry.value);
      return text;
    }
  return "-";
}

void run(const ListOptions& options) {
  const auto settings = merit_settings(options.merit_flags);
  const std::vector<codes::Merit> merits(codes::kAllMerits.begin(), codes::kAllMerits.end());
  if (!options.json)
    std::printf("%-18s %-52s %9s %9s %9s %8s %8s %6s %9s\n", "name", "code", "maxmin", "avgmin",
                "pairs", "single", "joint", "xseed", "mse");
  for (const auto& entry : codes::code_library()) {
    const auto report = codes::make_code_report(codes::to_code(entry), merits, settings);
    if (options.json) {
      auto object = codes::to_json(report, settings);
      object["origin"] = entry.origin;
      std::cout << object.dump() << "\n";
      continue;
    }
    std::string ratio = "-";
    if (report.joint_ratio_to_best_seed) {
      char text[16];
      std::snprintf(text, sizeof text, "%.2f", *report.joint_ratio_to_best_seed);
      ratio = text;
    }
    std::printf("%-18s %-52s %9s %9s %9s %8s %8s %6s %9s\n", std::string(entry.name).c_str(),
                std::string(entry.digits).c_str(),
                cell(report, codes::Merit::kMaxMin, "%.3f").c_str(),
                cell(report, codes::Merit::kAvgMin, "%.3f").c_str(),
                cell(report, codes::Merit::kPairs, "%.3f").c_str(),
                cell(report, codes::Merit::kSingle, "%.4f").c_str(),
                cell(report, codes::Merit::kJoint, "%.1f").c_str(), ratio.c_str(),
                cell(report, codes::Merit::kMse, "%.5f").c_str());
  }
  if (!options.json) {
    const auto& light = settings.light;
    std::printf(
        "\nmaxmin/avgmin/pairs in dB on the seed's 64-point grid; joint in e- (E %g e-, cap %g, "
        "read noise %g e-),\nxseed = joint / best seed triplet; mse lower is better. "
        "'flutterscan codes score NAME' shows one code in full.\n",
        light.electrons, light.cap, light.read_noise);
  }
}

}  // namespace

void add_codes_list(CLI::App& codes) {
  auto options = std::make_shared<ListOptions>();
  CLI::App* command = codes.add_subcommand("list", "The built-in code library, with every merit");
  command->add_flag("--json", options->json, "one JSON object per code, one per line");
  add_merit_flags(*command, options->merit_flags);
  command->callback([options] { run(*options); });
}

}  // namespace flutterscan::app
