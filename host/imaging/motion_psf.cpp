#include "imaging/motion_psf.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

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

/// Si(x), the integral of sin(t) / t from 0 to x: its power series up to |x| =
/// 20 (cancellation costs under 8 of the 16 digits there), the asymptotic
/// series beyond (its smallest term is below 1e-9 from x = 20).
double sine_integral(double x) {
  const double a = std::abs(x);
  double value;
  if (a <= 20) {
    double term = a, sum = a;  // term: (-1)^n a^(2n+1) / (2n+1)!
    for (int n = 1; n < 80; ++n) {
      term *= -a * a / ((2.0 * n) * (2.0 * n + 1));
      const double add = term / (2.0 * n + 1);
      sum += add;
      if (std::abs(add) < 1e-17 * std::abs(sum)) break;
    }
    value = sum;
  } else {
    double f = 0, g = 0, f_term = 1 / a, g_term = 1 / (a * a);
    for (int k = 0; k < 10; ++k) {
      f += f_term;
      g += g_term;
      f_term *= -(2.0 * k + 1) * (2.0 * k + 2) / (a * a);
      g_term *= -(2.0 * k + 2) * (2.0 * k + 3) / (a * a);
    }
    value = std::numbers::pi / 2 - f * std::cos(a) - g * std::sin(a);
  }
  return x < 0 ? -value : value;
}

/// One slot through sinc interpolation: tap j (kBandLimitedLead taps before the
/// motion's start) gets the mean of sinc(j - d) over d in the slot, within
/// kBandLimitedLead taps of it; the slot's light kept whole (the tails cut).
void deposit_band_limited(std::vector<double>& taps, double start, double width, double weight) {
  const double end = start + width;
  const int first = static_cast<int>(std::floor(start)) - kBandLimitedLead;
  const int last = static_cast<int>(std::ceil(end)) + kBandLimitedLead;
  std::vector<double> shape;
  double sum = 0;
  for (int j = first; j <= last; ++j) {
    double v;
    if (width > 1e-9) {
      v = (sine_integral(std::numbers::pi * (j - start)) -
           sine_integral(std::numbers::pi * (j - end))) /
          (std::numbers::pi * width);
    } else {
      const double u = std::numbers::pi * (j - start);
      v = u == 0 ? 1.0 : std::sin(u) / u;
    }
    shape.push_back(v);
    sum += v;
  }
  if (!(std::abs(sum) > 1e-12)) return;
  for (int j = first; j <= last; ++j) {
    const long index = static_cast<long>(j) + kBandLimitedLead;
    if (index < 0 || index >= static_cast<long>(taps.size())) continue;
    taps[static_cast<std::size_t>(index)] +=
        weight * shape[static_cast<std::size_t>(j - first)] / sum;
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

int pixel_model_lead(PixelModel model) {
  return model == PixelModel::kBandLimited ? kBandLimitedLead : 0;
}

void undo_psf_lead(Plane& latent, int lead) {
  if (lead <= 0 || latent.width <= lead) return;
  for (int y = 0; y < latent.height; ++y) {
    const auto row = latent.row(y);
    std::copy_backward(row.begin(), row.end() - lead, row.end());
    std::fill(row.begin(), row.begin() + lead, row[static_cast<std::size_t>(lead)]);
  }
}

std::size_t pixel_model_taps(double end_px, PixelModel model) {
  const auto whole = static_cast<std::size_t>(std::floor(std::max(0.0, end_px)));
  switch (model) {
    case PixelModel::kBoxAperture:
      return whole + 2;
    case PixelModel::kBandLimited:
      return whole + 2 + 2 * static_cast<std::size_t>(kBandLimitedLead);
    case PixelModel::kTapGrid:
      break;
  }
  return whole + 1;
}

void deposit_slot(std::vector<double>& taps, double start_px, double width_px, double weight,
                  PixelModel model) {
  if (taps.empty() || weight == 0) return;
  switch (model) {
    case PixelModel::kBoxAperture:
      deposit_aperture(taps, start_px, width_px, weight);
      return;
    case PixelModel::kBandLimited:
      deposit_band_limited(taps, start_px, width_px, weight);
      return;
    case PixelModel::kTapGrid:
      deposit_tap_grid(taps, start_px, width_px, weight);
      return;
  }
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

bool edges_move_forward(std::span<const double> edges) {
  return std::is_sorted(edges.begin(), edges.end());
}

}  // namespace flutterscan::imaging
