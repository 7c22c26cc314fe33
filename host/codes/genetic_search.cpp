// The seed's genetic algorithm (Appendix B) as it intends to work: roulette
// selection on fitness_offset + score, elites kept, one-point tail-swap
// crossover, per-gene mutation. Two defects of the printed code are fixed
// (docs/codes.md): the roulette summed the wrong individual's score, and the
// selected generation was overwritten by memcpy(next, pop) instead of replacing
// the population.

#include <algorithm>
#include <random>
#include <thread>
#include <vector>

#include "codes/incremental_spectra.hpp"
#include "codes/search_monitor.hpp"

namespace flutterscan::codes {
namespace {

using Rng = std::mt19937_64;

struct Individual {
  LedCode code;
  double objective = 0;
};

std::uint8_t random_gene(int leds, Rng& rng) {
  if (leds == 1) return static_cast<std::uint8_t>(rng() & 1U);
  return static_cast<std::uint8_t>(1U << std::uniform_int_distribution<int>(0, leds - 1)(rng));
}

/// Scores the population on `threads` threads, each with its own spectra buffer.
void score(std::vector<Individual>& population, const SearchOptions& options,
           std::vector<IncrementalSpectra>& evaluators) {
  const std::size_t threads = evaluators.size();
  const std::size_t share = (population.size() + threads - 1) / threads;
  std::vector<std::jthread> workers;
  for (std::size_t w = 0; w < threads; ++w)
    workers.emplace_back([&, w] {
      auto& evaluator = evaluators[w];
      const std::size_t end = std::min(population.size(), (w + 1) * share);
      for (std::size_t i = w * share; i < end; ++i) {
        evaluator.assign(population[i].code);
        population[i].objective = merit_objective(
            options.merit, merit_on_grid(options.merit, evaluator.spectra(), options.settings));
      }
    });
}

}  // namespace

SearchResult run_genetic_search(const SearchOptions& options, SearchMonitor& monitor) {
  const GeneticSettings& g = options.genetic;
  const auto size = static_cast<std::size_t>(g.population);
  const auto elites = static_cast<std::size_t>(g.elites);
  const int length = options.length;
  Rng rng(derive_seed(options.seed, 0));
  std::uniform_real_distribution<double> unit(0.0, 1.0);

  std::vector<Individual> population(size);
  for (auto& individual : population) {
    std::vector<std::uint8_t> genes(static_cast<std::size_t>(length));
    for (auto& gene : genes) gene = random_gene(options.leds, rng);
    individual.code = LedCode::from_masks(genes, options.leds).value();
  }
  const auto grid = merit_grid(options.merit, length, options.settings, search_grid_points(length));
  std::vector<IncrementalSpectra> evaluators(static_cast<std::size_t>(options.threads),
                                             IncrementalSpectra(population[0].code, grid));
  std::vector<Individual> next(size);
  std::vector<double> weight(size);

  SearchResult result;
  double pressure_sum = 0;
  int generation = 0;
  for (;; ++generation) {
    if (options.evaluations > 0 ? result.evaluations + g.population > options.evaluations
                                : generation > 0 && monitor.elapsed() >= options.seconds)
      break;
    score(population, options, evaluators);
    result.evaluations += g.population;
    monitor.add_evaluations(g.population);
    std::stable_sort(
        population.begin(), population.end(),
        [](const Individual& a, const Individual& b) { return a.objective > b.objective; });
    result.best = population[0].code;
    result.objective = population[0].objective;
    monitor.offer_best(result.objective);

    // Selection: roulette on offset + score (the printed code summed pop[i]
    // where it meant pop[j]).
    double sum = 0;
    for (std::size_t j = 0; j < size; ++j) {
      weight[j] = std::max(0.0, g.fitness_offset + population[j].objective);
      sum += weight[j];
    }
    const double pressure = sum > 0 ? weight[0] * static_cast<double>(size) / sum : 0.0;
    pressure_sum += pressure;
    monitor.set_generation(generation, pressure);
    for (std::size_t i = 0; i < elites; ++i) next[i] = population[i];
    for (std::size_t i = elites; i < size; ++i) {
      const double r = unit(rng) * sum;
      double running = 0;
      std::size_t pick = size - 1;
      for (std::size_t j = 0; j < size; ++j) {
        running += weight[j];
        if (running > r) {
          pick = j;
          break;
        }
      }
      next[i] = population[pick];
    }
    population.swap(next);  // the printed memcpy(next, pop) copied the other way

    // Crossover: swap tails from a random cut with a random non-elite partner.
    std::uniform_int_distribution<std::size_t> partner(elites, size - 1);
    std::uniform_int_distribution<int> cut(0, length - 1);
    for (std::size_t i = elites; i < size; ++i) {
      if (unit(rng) >= g.crossover) continue;
      const std::size_t j = partner(rng);
      for (int slot = cut(rng); slot < length; ++slot) {
        const std::uint8_t mine = population[i].code.mask(slot);
        population[i].code.set_mask(slot, population[j].code.mask(slot));
        population[j].code.set_mask(slot, mine);
      }
    }
    // Mutation: every gene of every non-elite.
    for (std::size_t i = elites; i < size; ++i)
      for (int slot = 0; slot < length; ++slot)
        if (unit(rng) < g.mutation)
          population[i].code.set_mask(slot, random_gene(options.leds, rng));
  }
  result.mean_selection_pressure = generation > 0 ? pressure_sum / generation : 0.0;
  return result;
}

}  // namespace flutterscan::codes
