#include "codes/search.hpp"

#include <chrono>
#include <future>
#include <thread>

#include "codes/search_monitor.hpp"

namespace flutterscan::codes {

int search_grid_points(int length) {
  return 4 * length + 1;
}

std::string search_options_problem(SearchAlgorithm algorithm, const SearchOptions& options) {
  if (options.leds < 1 || options.leds > kMaxLeds) return "--leds must be 1 to 4";
  if (options.length < 1 || options.length > kMaxSlots) return "--length must be 1 to 256";
  if ((options.seconds > 0) == (options.evaluations > 0))
    return "give exactly one budget: --seconds or --evaluations";
  if (options.threads < 1) return "--threads must be at least 1";
  LedCode probe;
  {
    std::array<std::uint8_t, kMaxSlots> masks{};
    masks.fill(1);
    probe =
        LedCode::from_masks({masks.data(), static_cast<std::size_t>(options.length)}, options.leds)
            .value();
  }
  if (auto why = merit_inapplicable(options.merit, probe, options.settings); !why.empty())
    return why;
  const auto& c = options.constraints;
  if (c.min_on_slots < 0) return "--min-on must not be negative";
  if (options.leds == 1) {
    if (c.balanced) return "--balanced needs a code of several LEDs";
    if (c.ones > options.length)
      return "--ones " + std::to_string(c.ones) + " is more than the code's " +
             std::to_string(options.length) + " slots";
    if (c.ones >= 0 && c.ones < c.min_on_slots) return "--ones is below --min-on";
    if (c.min_on_slots > options.length) return "--min-on is more than the code's slots";
  } else {
    if (c.ones >= 0) return "--ones is for one-LED codes (--leds 1)";
    if (c.min_on_slots * options.leds > options.length)
      return "--min-on " + std::to_string(c.min_on_slots) + " for " + std::to_string(options.leds) +
             " LEDs needs more than " + std::to_string(options.length) + " slots";
  }
  if (algorithm == SearchAlgorithm::kGenetic) {
    if (c.balanced || c.min_on_slots > 0 || c.ones >= 0)
      return "the genetic search takes no constraints; use the annealing search";
    const auto& g = options.genetic;
    if (g.population < 2 || g.elites < 0 || g.elites >= g.population)
      return "the genetic population must exceed its elites";
    if (options.evaluations > 0 && options.evaluations < g.population)
      return "--evaluations must cover at least one generation (" + std::to_string(g.population) +
             " evaluations)";
    if (g.crossover < 0 || g.crossover > 1 || g.mutation < 0 || g.mutation > 1)
      return "crossover and mutation rates must lie in 0..1";
  }
  return {};
}

Result<SearchResult, std::string> search_codes(SearchAlgorithm algorithm,
                                               const SearchOptions& options) {
  if (auto why = search_options_problem(algorithm, options); !why.empty())
    return Result<SearchResult, std::string>::failure(why);
  SearchMonitor monitor(options);
  auto work = std::async(std::launch::async, [&] {
    return algorithm == SearchAlgorithm::kGenetic ? run_genetic_search(options, monitor)
                                                  : run_anneal_search(options, monitor);
  });
  using namespace std::chrono_literals;
  while (work.wait_for(200ms) != std::future_status::ready)
    if (options.on_progress) options.on_progress(monitor.snapshot());
  SearchResult result = work.get();
  result.seconds = monitor.elapsed();
  if (options.on_progress) options.on_progress(monitor.snapshot());
  return Result<SearchResult, std::string>::success(result);
}

}  // namespace flutterscan::codes
