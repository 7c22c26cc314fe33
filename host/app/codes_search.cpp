// `flutterscan codes search --merit M (--seconds S | --evaluations N) --seed N ...`

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>

#include "app/cli_errors.hpp"
#include "app/code_arguments.hpp"
#include "app/commands.hpp"
#include "codes/code_report.hpp"
#include "codes/search.hpp"

namespace flutterscan::app {
namespace {

struct SearchFlags {
  int leds = 3;
  int length = 52;
  std::string merit = "joint";
  std::string algorithm = "anneal";
  double seconds = 0;
  long long evaluations = 0;
  std::uint64_t seed = 1;
  int threads = 2;
  int ones = -1;
  int min_on = 0;
  bool balanced = false;
  std::string ga_rates = "code";
  int population = 1000;
  bool json = false;
  MeritFlags merit_flags;
};

void show_progress(const codes::SearchProgress& progress, codes::Merit merit) {
  const double best = codes::merit_from_objective(merit, progress.best_objective);
  std::fprintf(stderr, "\r  %6.1f s  %8.2f M evaluations  best %s %.4f %s", progress.seconds,
               progress.evaluations / 1e6, std::string(codes::merit_name(merit)).c_str(), best,
               std::string(codes::merit_unit(merit)).c_str());
  if (progress.generation >= 0)
    std::fprintf(stderr, "  generation %d, selection pressure %.4f", progress.generation,
                 progress.selection_pressure);
  std::fprintf(stderr, "   ");
  std::fflush(stderr);
}

void check_budget(const SearchFlags& flags) {
  if (flags.seconds != 0 && !(std::isfinite(flags.seconds) && flags.seconds > 0))
    throw UsageError("--seconds must be a finite number of seconds > 0, not " +
                     std::to_string(flags.seconds));
  if (flags.evaluations < 0)
    throw UsageError("--evaluations must be > 0, not " + std::to_string(flags.evaluations));
}

void run(const SearchFlags& flags) {
  check_budget(flags);
  codes::SearchOptions options;
  const auto merits = parse_merits({flags.merit});
  if (merits.size() != 1) throw UsageError("--merit takes one merit for a search");
  options.merit = merits.front();
  options.leds = flags.leds;
  options.length = flags.length;
  options.settings = merit_settings(flags.merit_flags);
  options.constraints.balanced = flags.balanced;
  options.constraints.min_on_slots = flags.min_on;
  options.constraints.ones = flags.ones;
  options.seconds = flags.seconds;
  options.evaluations = flags.evaluations;
  options.seed = flags.seed;
  options.threads = flags.threads;
  options.genetic.population = flags.population;
  if (flags.ga_rates == "prose") {
    options.genetic.crossover = 0.9;
    options.genetic.mutation = 0.01;
  }
  const auto algorithm = flags.algorithm == "genetic" ? codes::SearchAlgorithm::kGenetic
                                                      : codes::SearchAlgorithm::kAnneal;
  const bool terminal = isatty(STDERR_FILENO) != 0;
  if (terminal)
    options.on_progress = [&](const codes::SearchProgress& p) { show_progress(p, options.merit); };
  const auto result = codes::search_codes(algorithm, options);
  if (!result.ok()) throw UsageError(result.error());
  if (terminal) std::fprintf(stderr, "\n");
  const auto& found = result.value();

  const std::vector<codes::Merit> all(codes::kAllMerits.begin(), codes::kAllMerits.end());
  const auto report = codes::make_code_report(found.best, all, options.settings);
  if (flags.json) {
    auto object = codes::to_json(report, options.settings);
    object["search"] = {{"merit", flags.merit},     {"algorithm", flags.algorithm},
                        {"seed", flags.seed},       {"evaluations", found.evaluations},
                        {"seconds", found.seconds}, {"threads", flags.threads}};
    if (algorithm == codes::SearchAlgorithm::kGenetic)
      object["search"]["mean_selection_pressure"] = found.mean_selection_pressure;
    std::cout << object.dump() << "\n";
    return;
  }
  std::printf("best code after %lld evaluations in %.1f s (%s, seed %llu):\n", found.evaluations,
              found.seconds, flags.algorithm.c_str(), static_cast<unsigned long long>(flags.seed));
  if (algorithm == codes::SearchAlgorithm::kGenetic)
    std::printf("mean selection pressure (best's expected copies / average's): %.4f\n",
                found.mean_selection_pressure);
  std::cout << codes::to_text(report, options.settings);
}

}  // namespace

void add_codes_search(CLI::App& codes) {
  auto flags = std::make_shared<SearchFlags>();
  CLI::App* command =
      codes.add_subcommand("search", "Search for the code that maximises a merit (mse: minimises)");
  command->add_option("--leds", flags->leds, "LEDs (one-of-N codes; 1 = a single flutter code)")
      ->check(CLI::Range(1, 4))
      ->capture_default_str();
  command->add_option("--length", flags->length, "slots per exposure")
      ->check(CLI::Range(1, 256))
      ->capture_default_str();
  command->add_option("--merit", flags->merit, "joint, maxmin, avgmin, pairs, single or mse")
      ->capture_default_str();
  command
      ->add_option("--algorithm", flags->algorithm,
                   "anneal (incremental annealing) or genetic (the seed's GA, fixed)")
      ->check(CLI::IsMember({"anneal", "genetic"}))
      ->capture_default_str();
  auto* seconds = command->add_option("--seconds", flags->seconds, "time budget, seconds");
  auto* evaluations =
      command->add_option("--evaluations", flags->evaluations,
                          "evaluation budget: with --seed the result is the same every run");
  seconds->excludes(evaluations);
  command->add_option("--seed", flags->seed, "random seed")->capture_default_str();
  command->add_option("--threads", flags->threads, "threads (annealing chains)")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  command->add_option("--ones", flags->ones, "one-LED codes: exactly K on-slots");
  command->add_option("--min-on", flags->min_on, "every LED on in at least K slots");
  command->add_flag("--balanced", flags->balanced,
                    "on-slot counts differ by at most one (17/18/17)");
  command
      ->add_option("--ga-rates", flags->ga_rates,
                   "genetic: 'code' (crossover 0.95, mutation 0.015) or 'prose' (0.9, 0.01)")
      ->check(CLI::IsMember({"code", "prose"}))
      ->capture_default_str();
  command->add_option("--population", flags->population, "genetic: population size")
      ->capture_default_str();
  command->add_flag("--json", flags->json, "print one JSON object");
  add_merit_flags(*command, flags->merit_flags);
  command->callback([flags] { run(*flags); });
}

}  // namespace flutterscan::app
