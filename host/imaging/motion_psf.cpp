#include "imaging/motion_psf.hpp"

#include <algorithm>
#include <cmath>

namespace flutterscan::imaging {
namespace {

/// Integral of tri(x) = max(0, 1 - |x|) from -infinity to u.
double triangle_integral(double u) {
  if (u <= -1) return 0;
  if (u <= 0) return 0.5 * (u + 1) * (u + 1);
  if (u < 1) return 1 - 0.5 * (1 - u) * (1 - u);
  return 1;
}

/// One slot under the box aperture: tap j gets the mean of tri(j - d) over d in the slot.
void deposit_aperture(std::vector<double>& taps, double start, double width, double weight) {
  const std::size_t last = taps.size() - 1;
  const double end = start + width;
  const auto first = static_cast<std::size_t>(std::max(0.0, std::floor(start)));
  const auto stop = std::min(last, static_cast<std::size_t>(std::floor(end)) + 1);
  if (width <= 1e-9) {
    // The scene stood still at `start` while the slot was lit: linear interpolation.
    for (std::size_t j = first; j <= stop; ++j)
      taps[j] += weight * std::max(0.0, 1 - std::abs(static_cast<double>(j) - start));
    return;
  }
  for (std::size_t j = first; j <= stop; ++j) {
    const double x = static_cast<double>(j);
    taps[j] += weight * (triangle_integral(x - start) - triangle_integral(x - end)) / width;
  }
}

void deposit_tap_grid(std::vector<double>& taps, double start, double width, double weight) {
  const std::size_t last = taps.size() - 1;
  if (width <= 1e-12) {
    const auto j = static_cast<std::size_t>(std::floor(std::max(0.0, start)));
    taps[std::min(j, last)] += weight;
    return;
  }
  const double end = start + width;
  for (auto j = static_cast<std::size_t>(std::floor(std::max(0.0, start))); j <= last; ++j) {
    const double lo = std::max(start, static_cast<double>(j));
    const double hi = std::min(end, static_cast<double>(j + 1));
    if (hi <= lo) {
      if (static_cast<double>(j) >= end) break;
      continue;
    }
    taps[j] += weight * (hi - lo) / width;
  }
}

}  // namespace

std::size_t pixel_model_taps(double end_px, PixelModel model) {
  const auto whole = static_cast<std::size_t>(std::floor(std::max(0.0, end_px)));
  return model == PixelModel::kBoxAperture ? whole + 2 : whole + 1;
}

void deposit_slot(std::vector<double>& taps, double start_px, double width_px, double weight,
                  PixelModel model) {
  if (taps.empty() || weight == 0) return;
  if (model == PixelModel::kBoxAperture)
    deposit_aperture(taps, start_px, width_px, weight);
  else
    deposit_tap_grid(taps, start_px, width_px, weight);
}

std::vector<double> accelerating_slot_edges(int slots, double blur_px, double speed_ratio) {
  // v(u) = v0 (1 + (r - 1) u) over the exposure time u in [0, 1], travelling
  // blur in all: x(u) = blur (u + (r - 1) u^2 / 2) / (1 + (r - 1) / 2).
  const double r = std::max(0.0, speed_ratio);
  std::vector<double> edges(static_cast<std::size_t>(std::max(slots, 0)) + 1, 0.0);
  for (int t = 0; t <= slots; ++t) {
    const double u = static_cast<double>(t) / slots;
    edges[static_cast<std::size_t>(t)] =
        blur_px * (u + 0.5 * (r - 1) * u * u) / (1 + 0.5 * (r - 1));
  }
  return edges;
}

void add_block_offsets(std::vector<double>& edges, std::span<const double> offsets) {
  if (offsets.empty() || edges.size() < 2) return;
  const double slots = static_cast<double>(edges.size() - 1);
  const double blocks = static_cast<double>(offsets.size() + 1);
  const auto offset_at = [&](std::size_t knot) {
    return knot == 0 || knot > offsets.size() ? 0.0 : offsets[knot - 1];
  };
  for (std::size_t t = 0; t < edges.size(); ++t) {
    const double position = static_cast<double>(t) / slots * blocks;  // in blocks
    const auto knot = std::min(static_cast<std::size_t>(position), offsets.size());
    const double f = position - static_cast<double>(knot);
    edges[t] += (1 - f) * offset_at(knot) + f * offset_at(knot + 1);
  }
}

}  // namespace flutterscan::imaging
