// Merit evaluations per second: spectra rebuilt by FFT ("full") versus kept
// up to date by IncrementalSpectra after a one-slot move ("incremental").

#include <benchmark/benchmark.h>

#include <bit>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <string_view>
#include <vector>

#include "codes/incremental_spectra.hpp"
#include "codes/merits.hpp"
#include "codes/search.hpp"

namespace {

using flutterscan::LedCode;
using namespace flutterscan::codes;

// The seed's 3-LED code and Raskar's one-LED code, 52 slots each.
constexpr std::string_view kSeedCode = "2212441414112412441224111241244244242212442211444144";
constexpr std::string_view kRaskarCode = "1010000111000001010000110011110111010111001001100111";

struct Case {
  Merit merit;
  std::string_view digits;
  int leds;
};

LedCode parse_or_die(std::string_view digits, int leds) {
  const auto code = LedCode::parse(digits, leds);
  if (!code) {
    std::fprintf(stderr, "codes_bench: bad start code %.*s\n", static_cast<int>(digits.size()),
                 digits.data());
    std::abort();
  }
  return code.value();
}

// A precomputed move: `slot` moves `step` LEDs on (mod leds); one-LED codes toggle.
struct Move {
  int slot;
  int step;
};

std::vector<Move> random_moves(int length, int leds, std::size_t count) {
  std::mt19937_64 rng(1);
  std::uniform_int_distribution<int> slot(0, length - 1);
  std::uniform_int_distribution<int> step(1, leds > 1 ? leds - 1 : 1);
  std::vector<Move> moves(count);
  for (auto& move : moves) move = {slot(rng), step(rng)};
  return moves;
}

// The mask `move` gives a slot that holds `mask`; always differs from `mask`.
std::uint8_t moved_mask(std::uint8_t mask, int step, int leds) {
  if (leds == 1) return mask ^ 1U;
  const int led = (std::countr_zero(mask) + step) % leds;
  return static_cast<std::uint8_t>(1U << led);
}

void bm_full(benchmark::State& state, Case c) {
  const MeritSettings settings;
  const LedCode code = parse_or_die(c.digits, c.leds);
  const int points = search_grid_points(code.length());
  for (auto _ : state) {
    const GridSpectra spectra = grid_spectra(c.merit, code, settings, points);
    benchmark::DoNotOptimize(merit_on_grid(c.merit, spectra, settings));
  }
  state.SetItemsProcessed(state.iterations());
}

void bm_incremental(benchmark::State& state, Case c) {
  const MeritSettings settings;
  const LedCode code = parse_or_die(c.digits, c.leds);
  IncrementalSpectra spectra(
      code, merit_grid(c.merit, code.length(), settings, search_grid_points(code.length())));
  const auto moves = random_moves(code.length(), code.leds(), 4096);
  std::size_t next = 0;
  for (auto _ : state) {
    const Move& move = moves[next];
    next = (next + 1) % moves.size();
    spectra.set_mask(move.slot, moved_mask(spectra.code().mask(move.slot), move.step, c.leds));
    benchmark::DoNotOptimize(merit_on_grid(c.merit, spectra.spectra(), settings));
  }
  state.SetItemsProcessed(state.iterations());
}

void register_all() {
  const Case cases[] = {
      {Merit::kMaxMin, kSeedCode, 3},
      {Merit::kSingle, kRaskarCode, 1},
      {Merit::kJoint, kSeedCode, 3},
      {Merit::kMse, kSeedCode, 3},
  };
  for (const Case& c : cases) {
    const std::string prefix = "BM_Merit/" + std::string(merit_name(c.merit));
    for (auto* bench :
         {benchmark::RegisterBenchmark((prefix + "/full").c_str(), bm_full, c),
          benchmark::RegisterBenchmark((prefix + "/incremental").c_str(), bm_incremental, c)})
      bench->Repetitions(5)->ReportAggregatesOnly(true);
  }
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  register_all();
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
