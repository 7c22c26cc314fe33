#pragma once
// Template body of minimise_over_frequency (spectrum.hpp).

#include <algorithm>
#include <cmath>
#include <utility>

namespace flutterscan::codes {

template <typename ValueAt>
Minimum minimise_over_frequency(std::span<const double> samples, ValueAt value_at) {
  const int n = static_cast<int>(samples.size());
  const double step = 0.5 / (n - 1);
  Minimum result;
  std::vector<std::pair<double, int>> local_minima;
  for (int j = 0; j < n; ++j) {
    const double left = j > 0 ? samples[j - 1] : samples[j];
    const double right = j + 1 < n ? samples[j + 1] : samples[j];
    if (samples[j] <= left && samples[j] <= right) local_minima.emplace_back(samples[j], j);
  }
  const auto grid_best = std::min_element(samples.begin(), samples.end());
  result.grid_value = *grid_best;
  result.grid_frequency = step * static_cast<double>(grid_best - samples.begin());
  result.refined_value = result.grid_value;
  result.refined_frequency = result.grid_frequency;

  constexpr int kCandidates = 4;
  const int keep = std::min<int>(kCandidates, static_cast<int>(local_minima.size()));
  std::partial_sort(local_minima.begin(), local_minima.begin() + keep, local_minima.end());
  const double golden = (std::sqrt(5.0) - 1.0) / 2.0;
  for (int c = 0; c < keep; ++c) {
    double a = std::max(0.0, step * (local_minima[c].second - 1));
    double b = std::min(0.5, step * (local_minima[c].second + 1));
    double x1 = b - golden * (b - a);
    double x2 = a + golden * (b - a);
    double f1 = value_at(x1);
    double f2 = value_at(x2);
    for (int iteration = 0; iteration < 60 && b - a > 1e-12; ++iteration) {
      if (f1 < f2) {
        b = x2;
        x2 = x1;
        f2 = f1;
        x1 = b - golden * (b - a);
        f1 = value_at(x1);
      } else {
        a = x1;
        x1 = x2;
        f1 = f2;
        x2 = a + golden * (b - a);
        f2 = value_at(x2);
      }
    }
    const double x = f1 < f2 ? x1 : x2;
    const double fx = std::min(f1, f2);
    if (fx < result.refined_value) {
      result.refined_value = fx;
      result.refined_frequency = x;
    }
  }
  return result;
}

}  // namespace flutterscan::codes
