// Simulated annealing over codes, one independent chain per thread. A move
// changes one slot's LED or swaps two slots; the spectra follow in O(grid)
// (IncrementalSpectra), so a move costs no FFT.

#include <cmath>
#include <random>
#include <thread>
#include <vector>

#include "codes/incremental_spectra.hpp"
#include "codes/search_monitor.hpp"

namespace flutterscan::codes {
namespace {

using Rng = std::mt19937_64;

/// Temperatures in dB of the objective: a move losing 1 dB is often taken at
/// the start, a move losing 0.01 dB rarely at the end.
constexpr double kStartTemperature = 1.0;
constexpr double kEndTemperature = 0.003;
/// Rebuild the spectra from the code this often, so rounding cannot accumulate.
constexpr long long kRefreshEvery = 1 << 16;
/// Budget checks and monitor updates happen every this many evaluations.
constexpr long long kCheckEvery = 256;

int uniform(Rng& rng, int n) {
  return std::uniform_int_distribution<int>(0, n - 1)(rng);
}

std::uint8_t led_mask(int led) {
  return static_cast<std::uint8_t>(1U << led);
}

/// On-slot targets of a balanced code: counts differ by at most one; the
/// extra slots go to LED 1 first (green: 52 slots become 17/18/17).
std::vector<int> balanced_counts(int leds, int length) {
  std::vector<int> counts(static_cast<std::size_t>(leds), length / leds);
  for (int i = 0; i < length % leds; ++i) ++counts[static_cast<std::size_t>((1 + i) % leds)];
  return counts;
}

LedCode initial_code(const SearchOptions& options, Rng& rng) {
  const auto& c = options.constraints;
  std::vector<std::uint8_t> masks(static_cast<std::size_t>(options.length));
  if (options.leds == 1) {
    const int ones = c.ones >= 0 ? c.ones : std::max(c.min_on_slots, options.length / 2);
    for (int t = 0; t < options.length; ++t) masks[static_cast<std::size_t>(t)] = t < ones;
  } else if (c.balanced) {
    const auto counts = balanced_counts(options.leds, options.length);
    std::size_t t = 0;
    for (int k = 0; k < options.leds; ++k)
      for (int i = 0; i < counts[static_cast<std::size_t>(k)]; ++i) masks[t++] = led_mask(k);
  } else {
    // Round-robin meets any feasible --min-on; shuffling keeps it.
    for (int t = 0; t < options.length; ++t)
      masks[static_cast<std::size_t>(t)] = led_mask(t % options.leds);
  }
  std::shuffle(masks.begin(), masks.end(), rng);
  return LedCode::from_masks(masks, options.leds).value();
}

/// A proposed change of up to two slots, with what it replaced (for undo).
struct Move {
  int count = 0;
  std::array<int, 2> slot{};
  std::array<std::uint8_t, 2> before{};
  std::array<std::uint8_t, 2> after{};
};

class MoveMaker {
 public:
  explicit MoveMaker(const SearchOptions& options) : options_(options) {
    const auto& c = options.constraints;
    swaps_only_ = c.balanced || (options.leds == 1 && c.ones >= 0);
  }

  /// A random move that keeps every constraint.
  Move propose(const LedCode& code, const GridSpectra& spectra, Rng& rng) const {
    for (;;) {
      Move move;
      if (swaps_only_ || std::uniform_real_distribution<double>(0, 1)(rng) < kSwapShare) {
        const int a = uniform(rng, code.length());
        const int b = uniform(rng, code.length());
        if (code.mask(a) == code.mask(b)) continue;
        move.count = 2;
        move.slot = {a, b};
        move.before = {code.mask(a), code.mask(b)};
        move.after = {code.mask(b), code.mask(a)};
        return move;
      }
      const int t = uniform(rng, code.length());
      const std::uint8_t before = code.mask(t);
      std::uint8_t after;
      if (options_.leds == 1) {
        after = before ^ 1U;
      } else {
        const int old_led = std::countr_zero(before);
        after = led_mask((old_led + 1 + uniform(rng, options_.leds - 1)) % options_.leds);
      }
      // Turning an LED off in this slot must leave it --min-on slots.
      const int losing = options_.leds == 1 ? (before ? 0 : -1) : std::countr_zero(before);
      if (losing >= 0 &&
          spectra.on_slots[static_cast<std::size_t>(losing)] <= options_.constraints.min_on_slots)
        continue;
      move.count = 1;
      move.slot[0] = t;
      move.before[0] = before;
      move.after[0] = after;
      return move;
    }
  }

 private:
  static constexpr double kSwapShare = 0.3;
  const SearchOptions& options_;
  bool swaps_only_ = false;
};

struct ChainResult {
  LedCode best;
  double objective = -INFINITY;
};

ChainResult run_chain(const SearchOptions& options, int chain, long long budget,
                      SearchMonitor& monitor) {
  Rng rng(derive_seed(options.seed, static_cast<std::uint64_t>(chain)));
  const MoveMaker moves(options);
  IncrementalSpectra state(initial_code(options, rng),
                           merit_grid(options.merit, options.length, options.settings,
                                      search_grid_points(options.length)));
  const auto objective = [&] {
    return merit_objective(options.merit,
                           merit_on_grid(options.merit, state.spectra(), options.settings));
  };
  double current = objective();
  ChainResult result{state.code(), current};
  monitor.offer_best(current);

  std::uniform_real_distribution<double> unit(0.0, 1.0);
  double temperature = kStartTemperature;
  long long done = 0;
  for (;;) {
    if (done % kCheckEvery == 0) {
      if (done > 0) monitor.add_evaluations(kCheckEvery);
      if (budget > 0 ? done >= budget : monitor.elapsed() >= options.seconds) break;
      const double fraction = std::min(1.0, monitor.fraction(done, budget));
      temperature = kStartTemperature * std::pow(kEndTemperature / kStartTemperature, fraction);
    }
    if (budget > 0 && done >= budget) break;
    const Move move = moves.propose(state.code(), state.spectra(), rng);
    for (int i = 0; i < move.count; ++i) state.set_mask(move.slot[i], move.after[i]);
    const double candidate = objective();
    ++done;
    if (candidate >= current || unit(rng) < std::exp((candidate - current) / temperature)) {
      current = candidate;
      if (current > result.objective) {
        result = {state.code(), current};
        monitor.offer_best(current);
      }
    } else {
      for (int i = move.count - 1; i >= 0; --i) state.set_mask(move.slot[i], move.before[i]);
    }
    if (done % kRefreshEvery == 0) {
      state.refresh();
      current = objective();
    }
  }
  monitor.add_evaluations(done % kCheckEvery);
  return result;
}

}  // namespace

SearchResult run_anneal_search(const SearchOptions& options, SearchMonitor& monitor) {
  const int chains = options.threads;
  std::vector<ChainResult> results(static_cast<std::size_t>(chains));
  std::vector<long long> budgets(static_cast<std::size_t>(chains), 0);
  if (options.evaluations > 0)
    for (int i = 0; i < chains; ++i)
      budgets[static_cast<std::size_t>(i)] =
          options.evaluations / chains + (i < options.evaluations % chains ? 1 : 0);
  {
    std::vector<std::jthread> threads;
    for (int i = 0; i < chains; ++i)
      threads.emplace_back([&, i] {
        results[static_cast<std::size_t>(i)] =
            run_chain(options, i, budgets[static_cast<std::size_t>(i)], monitor);
      });
  }
  SearchResult out;
  out.objective = -INFINITY;
  for (const auto& r : results)  // ties go to the lower chain: deterministic
    if (r.objective > out.objective) {
      out.best = r.best;
      out.objective = r.objective;
    }
  out.evaluations = monitor.snapshot().evaluations;
  return out;
}

}  // namespace flutterscan::codes
