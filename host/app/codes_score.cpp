// `flutterscan codes score CODE... [--merit M] [--json]`

#include <algorithm>
#include <iostream>
#include <memory>

#include "app/cli_errors.hpp"
#include "app/code_arguments.hpp"
#include "app/commands.hpp"
#include "codes/code_report.hpp"

namespace flutterscan::app {
namespace {

struct ScoreOptions {
  std::vector<std::string> codes;
  std::vector<std::string> merits;
  int leds = 0;
  bool one_of_n = false;
  bool json = false;
  MeritFlags merit_flags;
};

void run(const ScoreOptions& options) {
  const auto merits = parse_merits(options.merits);
  const auto settings = merit_settings(options.merit_flags);
  std::vector<LedCode> codes;  // parse every argument before printing anything
  const bool asks_joint = std::any_of(merits.begin(), merits.end(), [](codes::Merit m) {
    return m == codes::Merit::kJoint || m == codes::Merit::kMse;
  });
  for (const auto& argument : options.codes) {
    codes.push_back(parse_code_argument(argument, options.leds, options.one_of_n));
    const auto& crosstalk = settings.light.crosstalk;
    if (asks_joint && crosstalk && crosstalk->leds != codes.back().leds())
      throw UsageError("--crosstalk has " + std::to_string(crosstalk->leds) +
                       " columns (LEDs) but code '" + argument + "' has " +
                       std::to_string(codes.back().leds()) + " LEDs");
  }
  for (std::size_t i = 0; i < codes.size(); ++i) {
    const auto report = codes::make_code_report(codes[i], merits, settings);
    if (options.json)
      std::cout << codes::to_json(report, settings).dump() << "\n";
    else
      std::cout << (i > 0 ? "\n" : "") << codes::to_text(report, settings);
  }
}

}  // namespace

void add_codes_score(CLI::App& codes) {
  auto options = std::make_shared<ScoreOptions>();
  CLI::App* command = codes.add_subcommand(
      "score", "Print every merit of each code (digits such as 2212441414..., or a library name)");
  command->add_option("code", options->codes, "codes: digit strings or library names")->required();
  command->add_option(
      "--merit", options->merits,
      "merits to compute (maxmin, avgmin, pairs, single, joint, mse); all by default");
  command->add_option("--leds", options->leds, "LEDs in the code (default: inferred)")
      ->check(CLI::Range(1, 4));
  command->add_flag("--one-of-n", options->one_of_n, "require exactly one LED per slot");
  command->add_flag("--json", options->json, "one JSON object per code, one per line");
  add_merit_flags(*command, options->merit_flags);
  command->callback([options] { run(*options); });
}

}  // namespace flutterscan::app
