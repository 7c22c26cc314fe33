#pragma once
// Code search: the seed's genetic algorithm (fixed) and simulated annealing
// with incremental spectra. Both maximise merit_objective() (a dB scale) and
// stop on a time or an evaluation budget; with an evaluation budget and a
// seed the result is the same on every run.

#include <cstdint>
#include <functional>
#include <string>

#include "codes/merits.hpp"

namespace flutterscan::codes {

enum class SearchAlgorithm { kAnneal, kGenetic };

/// \brief Constraints on the codes a search may return (annealing only).
struct SearchConstraints {
  int min_on_slots = 0;   ///< every LED on in at least this many slots
  bool balanced = false;  ///< on-slot counts differ by at most one (17/18/17 for 52 slots)
  int ones = -1;          ///< one-LED codes: exactly this many on-slots (-1: free)
};

/// \brief The seed's GA settings. Defaults are its Appendix B code; its prose
/// says crossover 0.9 and mutation 0.01.
struct GeneticSettings {
  int population = 1000;
  double crossover = 0.95;
  double mutation = 0.015;  ///< per gene
  int elites = 3;
  double fitness_offset = 1000;  ///< roulette weight is offset + objective
};

struct SearchProgress {
  long long evaluations = 0;
  double seconds = 0;
  double best_objective = 0;
  int generation = -1;            ///< genetic only
  double selection_pressure = 0;  ///< genetic only: best / mean roulette weight
};

struct SearchOptions {
  Merit merit = Merit::kJoint;
  int leds = 3;
  int length = 52;
  MeritSettings settings;
  SearchConstraints constraints;
  double seconds = 0;         ///< time budget (> 0), or
  long long evaluations = 0;  ///< evaluation budget (> 0): deterministic
  std::uint64_t seed = 1;
  int threads = 2;
  GeneticSettings genetic;
  /// Called about five times a second from the calling thread.
  std::function<void(const SearchProgress&)> on_progress;
};

struct SearchResult {
  LedCode best;
  double objective = 0;  ///< on the search grid
  long long evaluations = 0;
  double seconds = 0;
  double mean_selection_pressure = 0;  ///< genetic only
};

/// \brief Checks the options; empty when they are consistent.
std::string search_options_problem(SearchAlgorithm algorithm, const SearchOptions& options);

/// \brief Runs the search. Fails with a message when the options are inconsistent.
Result<SearchResult, std::string> search_codes(SearchAlgorithm algorithm,
                                               const SearchOptions& options);

/// \brief Number of dense-grid samples the search judges joint and mse on.
int search_grid_points(int length);

}  // namespace flutterscan::codes
