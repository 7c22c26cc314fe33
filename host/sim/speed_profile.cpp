#include "sim/speed_profile.hpp"

#include <algorithm>
#include <random>

#include "imaging/motion_psf.hpp"

namespace flutterscan::sim {

std::vector<double> jittered_slot_boundaries(int slots, double blur_px, double rms,
                                             std::uint64_t seed) {
  std::vector<double> boundaries(static_cast<std::size_t>(slots) + 1, 0.0);
  if (rms <= 0) {
    for (int t = 0; t <= slots; ++t)
      boundaries[static_cast<std::size_t>(t)] = t * (blur_px / slots);
    return boundaries;
  }
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<double> step(static_cast<std::size_t>(slots));
  double total = 0;
  for (double& s : step) {
    s = std::max(0.0, 1.0 + rms * normal(rng));
    total += s;
  }
  const double scale = total > 0 ? blur_px / total : 0.0;
  for (int t = 0; t < slots; ++t)
    boundaries[static_cast<std::size_t>(t) + 1] =
        boundaries[static_cast<std::size_t>(t)] + step[static_cast<std::size_t>(t)] * scale;
  return boundaries;
}

std::vector<double> accelerated_slot_boundaries(int slots, double blur_px, double relative_change) {
  const double a = std::clamp(relative_change, -1.99, 1.99);
  return imaging::accelerating_slot_edges(slots, blur_px, (2 + a) / (2 - a));
}

}  // namespace flutterscan::sim
