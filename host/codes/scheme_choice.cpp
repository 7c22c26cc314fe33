#include "codes/scheme_choice.hpp"

#include <array>
#include <charconv>
#include <cmath>
#include <limits>

#include "codes/library.hpp"

namespace flutterscan::codes {
namespace {

constexpr std::array<double, 6> kLight = {30, 100, 300, 1000, 3000, 10000};
constexpr std::array<double, 6> kReadNoise = {1, 2, 4, 8, 16, 30};

struct Cell {
  const char* winner;
  double margin_db;
};

// regime.txt of the run quoted in docs/algorithms.md: [read noise][light].
constexpr Cell kCap3[6][6] = {
    {{"snapshot-4", -0.56},
     {"snapshot-2", -2.29},
     {"snapshot-2", -2.80},
     {"snapshot-2", -1.49},
     {"snapshot-1", -0.47},
     {"snapshot-1", -0.45}},
    {{"found-mse", 0.14},
     {"snapshot-2", -0.51},
     {"snapshot-2", -2.31},
     {"snapshot-2", -1.42},
     {"snapshot-1", -0.33},
     {"snapshot-1", -0.43}},
    {{"snapshot-8", -0.37},
     {"found-mse", 1.59},
     {"snapshot-2", -0.57},
     {"snapshot-2", -1.12},
     {"found-mse", 0.14},
     {"snapshot-1", -0.28}},
    {{"snapshot-17", -0.27},
     {"found-mse", 2.06},
     {"found-mse", 2.96},
     {"found-mse", 0.09},
     {"found-mse", 0.97},
     {"found-mse", 0.26}},
    {{"snapshot-17", -0.26},
     {"snapshot-8", -0.13},
     {"found-mse", 3.79},
     {"found-mse", 3.12},
     {"found-mse", 1.56},
     {"found-mse", 1.96}},
    {{"snapshot-17", -0.21},
     {"snapshot-17", -0.23},
     {"found-mse", 1.98},
     {"found-mse", 5.40},
     {"found-mse", 3.10},
     {"found-mse", 4.32}},
};
constexpr Cell kCap8[6][6] = {
    {{"snapshot-2", -6.39},
     {"snapshot-2", -7.31},
     {"snapshot-2", -5.78},
     {"snapshot-1", -4.39},
     {"snapshot-1", -4.48},
     {"snapshot-1", -4.67}},
    {{"snapshot-2", -4.74},
     {"snapshot-2", -6.88},
     {"snapshot-2", -5.78},
     {"snapshot-1", -4.28},
     {"snapshot-1", -4.44},
     {"snapshot-1", -4.66}},
    {{"snapshot-4", -3.75},
     {"snapshot-2", -5.69},
     {"snapshot-2", -5.70},
     {"snapshot-1", -3.82},
     {"snapshot-1", -4.28},
     {"snapshot-1", -4.62}},
    {{"snapshot-8", -1.85},
     {"snapshot-4", -3.87},
     {"snapshot-2", -5.10},
     {"snapshot-2", -3.49},
     {"snapshot-1", -3.66},
     {"snapshot-1", -4.42}},
    {{"snapshot-8", -1.00},
     {"snapshot-4", -3.46},
     {"snapshot-2", -3.76},
     {"snapshot-2", -3.47},
     {"snapshot-1", -1.96},
     {"snapshot-1", -3.73}},
    {{"snapshot-8", -0.55},
     {"snapshot-8", -1.72},
     {"snapshot-4", -3.46},
     {"snapshot-2", -3.16},
     {"snapshot-2", -1.29},
     {"snapshot-1", -2.10}},
};

std::size_t nearest(const std::array<double, 6>& grid, double value) {
  std::size_t best = 0;
  double distance = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < grid.size(); ++i) {
    const double d = std::abs(std::log(value) - std::log(grid[i]));
    if (d < distance) {
      distance = d;
      best = i;
    }
  }
  return best;
}

LedCode scheme_code(const std::string& name) {
  if (auto snapshot = snapshot_code(name)) return *snapshot;
  return to_code(*find_library_code(name));
}

}  // namespace

std::optional<LedCode> snapshot_code(std::string_view name) {
  constexpr std::string_view kPrefix = "snapshot-";
  if (!name.starts_with(kPrefix)) return std::nullopt;
  const auto number = name.substr(kPrefix.size());
  int slots = 0;
  const auto [end, error] = std::from_chars(number.data(), number.data() + number.size(), slots);
  if (error != std::errc{} || end != number.data() + number.size() || slots < 1 ||
      slots > kSnapshotSlots)
    return std::nullopt;
  std::string digits(kSnapshotSlots, '0');
  digits.replace(0, static_cast<std::size_t>(slots), static_cast<std::size_t>(slots), '7');
  return LedCode::parse(digits, 3).value();
}

SchemeChoice choose_scheme(double electrons, double read_noise, double cap) {
  const std::size_t light = nearest(kLight, std::max(electrons, 1e-9));
  const std::size_t noise = nearest(kReadNoise, std::max(read_noise, 1e-9));
  const bool high_cap = cap > 5.5;
  const Cell& cell = (high_cap ? kCap8 : kCap3)[noise][light];
  SchemeChoice choice;
  choice.scheme = cell.winner;
  choice.code = scheme_code(choice.scheme);
  choice.margin_db = cell.margin_db;
  choice.cell_electrons = kLight[light];
  choice.cell_read_noise = kReadNoise[noise];
  choice.cell_cap = high_cap ? 8 : 3;
  return choice;
}

}  // namespace flutterscan::codes
