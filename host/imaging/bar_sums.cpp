#include "imaging/bar_sums.hpp"

#include <algorithm>
#include <cmath>
#include <span>
#include <vector>

#include "imaging/metrics.hpp"

namespace flutterscan::imaging {
namespace {

/// Adds `row` shifted by `shift` pixels (sample x takes the row at x + shift,
/// linearly interpolated, clamped to the row's ends) into `sum`.
void add_shifted(std::span<const float> row, double shift, std::span<float> sum) {
  const int width = static_cast<int>(sum.size()), last = static_cast<int>(row.size()) - 1;
  const int whole = static_cast<int>(std::floor(shift));
  const auto f = static_cast<float>(shift - whole);
  const float g = 1 - f;
  auto sample = [&](int x) { return row[static_cast<std::size_t>(std::clamp(x, 0, last))]; };
  // Where both neighbours lie inside the row: no clamp (the loop vectorises).
  const int inner0 = std::clamp(-whole, 0, width);
  const int inner1 = std::clamp(last - whole, inner0, width);
  for (int x = 0; x < inner0; ++x) sum[x] += g * sample(x + whole) + f * sample(x + whole + 1);
  const float* from = row.data();
  float* to = sum.data();
  for (int x = inner0; x < inner1; ++x) to[x] += g * from[x + whole] + f * from[x + whole + 1];
  for (int x = inner1; x < width; ++x) sum[x] += g * sample(x + whole) + f * sample(x + whole + 1);
}

/// Adds `row` read at `offset` + `scale` x for each sample x (linearly
/// interpolated, clamped to the row's ends) into `sum`. The shift, `offset` +
/// (`scale` - 1) x, changes slowly: over each run of samples where its whole
/// part holds, x reads the row at x + that whole part, its fraction a ramp.
void add_resampled(std::span<const float> row, double offset, double scale, std::span<float> sum) {
  if (scale == 1) {
    add_shifted(row, offset, sum);
    return;
  }
  const int width = static_cast<int>(sum.size()), last = static_cast<int>(row.size()) - 1;
  const double stretch = scale - 1;
  for (int x = 0; x < width;) {
    const int whole = static_cast<int>(std::floor(offset + stretch * x));
    // The first sample past x whose shift has another whole part (at least x + 1).
    const double crossing = ((stretch > 0 ? whole + 1 : whole) - offset) / stretch;
    const int end = std::clamp(
        stretch > 0 ? static_cast<int>(std::ceil(crossing)) : static_cast<int>(crossing) + 1, x + 1,
        width);
    // Where both neighbours lie inside the row: no clamp (the loop vectorises).
    const int inner0 = std::clamp(-whole, x, end), inner1 = std::clamp(last - whole, inner0, end);
    auto clamped = [&](int at) {
      const double p = std::clamp(offset + scale * at, 0.0, static_cast<double>(last));
      const int i = static_cast<int>(p);
      const auto f = static_cast<float>(p - i);
      sum[static_cast<std::size_t>(at)] += (1 - f) * row[static_cast<std::size_t>(i)] +
                                           f * row[static_cast<std::size_t>(std::min(i + 1, last))];
    };
    for (int at = x; at < inner0; ++at) clamped(at);
    const float* from = row.data() + whole;
    float* to = sum.data();
    const auto f0 = static_cast<float>(offset + stretch * inner0 - whole);
    const auto step = static_cast<float>(stretch);
    for (int at = inner0; at < inner1; ++at) {
      const float f = f0 + step * static_cast<float>(at - inner0);
      to[at] += from[at] + f * (from[at + 1] - from[at]);
    }
    for (int at = inner1; at < end; ++at) clamped(at);
    x = end;
  }
}

/// Row `y` of `plane` summed along `slope` over the rows [y - half_rows,
/// y + half_rows] that exist, over columns [first_column, first_column +
/// sum.size()), into `sum` (zeroed first); returns how many rows.
int sum_row(const Plane& plane, int y, const BarSlope& slope, int half_rows, int first_column,
            std::span<float> sum) {
  std::fill(sum.begin(), sum.end(), 0.0f);
  // On row y the bars' slope is linear along the row: at(origin_x, y) + rate (x - origin_x).
  const double at_origin = slope.at(slope.origin_x, y);
  const double rate = slope.at(slope.origin_x + 1, y) - at_origin;
  int count = 0;
  for (int k = -half_rows; k <= half_rows; ++k) {
    if (y + k < 0 || y + k >= plane.height) continue;
    // Column x reads row y + k at x + k (at_origin + rate (x - origin_x)).
    const double scale = 1 + k * rate;
    add_resampled(plane.row(y + k), k * (at_origin - rate * slope.origin_x) + scale * first_column,
                  scale, sum);
    ++count;
  }
  return count;
}

/// Contrast along the rows kept by summing along `slope`: the sums' squared
/// steps between neighbours, over every 8th row at least half_rows from the
/// ends.
double kept_contrast(const Plane& latent, const BarSlope& slope, int half_rows) {
  constexpr int kRowStep = 8;
  std::vector<float> sum(static_cast<std::size_t>(latent.width));
  double energy = 0;
  for (int y = half_rows; y < latent.height - half_rows; y += kRowStep) {
    sum_row(latent, y, slope, half_rows, 0, sum);
    float rows = 0;
    for (std::size_t x = 1; x < sum.size(); ++x)
      rows += (sum[x] - sum[x - 1]) * (sum[x] - sum[x - 1]);
    energy += rows;
  }
  return energy;
}

/// A tile's bars: how much of its contrast along the rows depends on the slope
/// its rows are summed along (8 either side), and the slope that keeps most.
struct TileBars {
  double strength = 0;  ///< the most contrast any slope 0.05 apart keeps, less their mean
  double slope = 0;     ///< the slope that keeps the most
};

/// Bars: much strength (summed along any other slope they blur); noise and
/// plain paper: about none; text and a lone edge: little.
TileBars tile_bars(const Plane& tile) {
  constexpr int kHalfRows = 8;
  constexpr double kStep = 0.05;
  const int steps = static_cast<int>(std::lround(kMaxBarSlope / kStep));
  TileBars bars;
  double most = 0, total = 0;
  for (int i = -steps; i <= steps; ++i) {
    const double c = kept_contrast(tile, {.at_origin = i * kStep}, kHalfRows);
    if (c > most) {
      most = c;
      bars.slope = i * kStep;
    }
    total += c;
  }
  bars.strength = most - total / (2 * steps + 1);
  return bars;
}

/// bar_slope() over the whole of `latent`, its origin the plane's centre.
BarSlope slope_over(const Plane& latent, int half_rows) {
  constexpr double kCoarse = 0.05, kFine = 0.01, kCoarseChange = 0.04;
  BarSlope best{.origin_x = latent.width / 2.0, .origin_y = latent.height / 2.0};
  double best_contrast = kept_contrast(latent, best, half_rows);
  auto consider = [&](double at_origin, double change) {
    BarSlope slope = best;
    slope.at_origin = at_origin;
    slope.per_column = change / latent.width;
    const double c = kept_contrast(latent, slope, half_rows);
    if (c > best_contrast) {
      best_contrast = c;
      best = slope;
    }
  };
  auto change = [&] { return best.per_column * latent.width; };
  // Around the best so far, `steps` either side `step` apart: the slope at the centre, or its
  // change.
  auto refine_slope = [&](double step, int steps) {
    const double centre = best.at_origin, now = change();
    for (int i = -steps; i <= steps; ++i) {
      const double slope = centre + i * step;
      if (i != 0 && std::abs(slope) <= kMaxBarSlope + 1e-9) consider(slope, now);
    }
  };
  auto refine_change = [&](double step, int steps) {
    const double centre = change(), slope = best.at_origin;
    for (int i = -steps; i <= steps; ++i) {
      const double c = centre + i * step;
      if (i != 0 && std::abs(c) <= kMaxSlopeChange + 1e-9) consider(slope, c);
    }
  };
  refine_slope(kCoarse, static_cast<int>(std::lround(kMaxBarSlope / kCoarse)));
  refine_slope(kFine, static_cast<int>(std::lround(kCoarse / kFine)) - 1);
  refine_change(kCoarseChange, static_cast<int>(std::lround(kMaxSlopeChange / kCoarseChange)));
  refine_slope(kFine, 3);
  refine_change(kFine, static_cast<int>(std::lround(kCoarseChange / kFine)) - 1);
  return best;
}

}  // namespace

Region bar_region(const Plane& latent) {
  constexpr int kTile = 64, kMinTile = 24;
  constexpr double kSlopeStep = 0.2 + 1e-9;
  if (latent.width < kMinTile || latent.height < kMinTile)
    return {0, 0, latent.width, latent.height};
  const int columns = (latent.width - kMinTile) / kTile + 1;
  const int rows = (latent.height - kMinTile) / kTile + 1;
  auto tile_region = [&](int i) {
    const int x = i % columns * kTile, y = i / columns * kTile;
    return Region{x, y, std::min(x + kTile, latent.width), std::min(y + kTile, latent.height)};
  };
  std::vector<TileBars> tiles;
  for (int i = 0; i < columns * rows; ++i) {
    const Region r = tile_region(i);
    tiles.push_back(tile_bars(latent.part(r.x0, r.y0, r.x1, r.y1)));
  }
  const auto strongest =
      static_cast<int>(std::max_element(tiles.begin(), tiles.end(),
                                        [](const TileBars& a, const TileBars& b) {
                                          return a.strength < b.strength;
                                        }) -
                       tiles.begin());
  if (tiles[static_cast<std::size_t>(strongest)].strength <= 0)
    return {0, 0, latent.width, latent.height};
  const double enough = tiles[static_cast<std::size_t>(strongest)].strength / 4;
  std::vector<bool> reached(tiles.size(), false);
  std::vector<int> next{strongest};
  reached[static_cast<std::size_t>(strongest)] = true;
  Region box = tile_region(strongest);
  while (!next.empty()) {
    const int i = next.back();
    next.pop_back();
    const Region r = tile_region(i);
    box = {std::min(box.x0, r.x0), std::min(box.y0, r.y0), std::max(box.x1, r.x1),
           std::max(box.y1, r.y1)};
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const int cx = i % columns + dx, cy = i / columns + dy;
        if (cx < 0 || cx >= columns || cy < 0 || cy >= rows) continue;
        const auto j = static_cast<std::size_t>(cy * columns + cx);
        if (reached[j] || tiles[j].strength < enough ||
            std::abs(tiles[j].slope - tiles[static_cast<std::size_t>(i)].slope) > kSlopeStep)
          continue;
        reached[j] = true;
        next.push_back(static_cast<int>(j));
      }
  }
  return box;
}

double BarSlope::at(double x, double y) const {
  // The perspective's denominator kept from nearing 0 (a vanishing point
  // inside the window is no label's): at least half.
  return (at_origin + per_column * (x - origin_x)) / std::max(0.5, 1 + per_column * (y - origin_y));
}

BarSlope bar_slope(const Plane& latent, int half_rows) {
  return bar_slope(latent, bar_region(latent), half_rows);
}

BarSlope bar_slope(const Plane& latent, const Region& box, int half_rows) {
  // Judged where the bars are: the rest of a window (text, a hand, the label's
  // and the belt's edges) pulls the slope elsewhere. Rows summed half_rows
  // beyond the box's, so that the rows judged are the box's.
  const int y0 = std::max(0, box.y0 - half_rows);
  const int y1 = std::min(latent.height, box.y1 + half_rows);
  BarSlope slope = slope_over(latent.part(box.x0, y0, box.x1, y1), half_rows);
  slope.origin_x += box.x0;
  slope.origin_y += y0;
  slope.judged_over = box;
  return slope;
}

std::vector<bool> rows_across_bars(const Plane& latent, const BarSlope& slope, int half_rows) {
  constexpr int kStrengthHalf = 8;
  constexpr double kWrongSlope = 0.15;
  const Region& box = slope.judged_over;
  std::vector<bool> across(static_cast<std::size_t>(latent.height), false);
  if (box.x1 - box.x0 < 2) return across;
  std::vector<float> sum(static_cast<std::size_t>(box.x1 - box.x0));
  // The squared steps along the box's columns of row y's 17 rows summed along `along`.
  auto kept = [&](int y, const BarSlope& along) {
    sum_row(latent, y, along, kStrengthHalf, box.x0, sum);
    double e = 0;
    for (std::size_t x = 1; x < sum.size(); ++x) {
      const double d = sum[x] - sum[x - 1];
      e += d * d;
    }
    return e;
  };
  std::vector<double> strength(static_cast<std::size_t>(latent.height));
  double strongest = 0;
  for (int y = 0; y < latent.height; ++y) {
    BarSlope steeper = slope, shallower = slope;
    steeper.at_origin += kWrongSlope;
    shallower.at_origin -= kWrongSlope;
    strength[static_cast<std::size_t>(y)] =
        kept(y, slope) - (kept(y, steeper) + kept(y, shallower)) / 2;
    strongest = std::max(strongest, strength[static_cast<std::size_t>(y)]);
  }
  if (strongest <= 0) return across;
  // Row y's rows [y - half_rows, y + half_rows] are covered by the 17-row sums
  // of rows [y - reach, y + reach].
  const int reach = std::max(0, half_rows - kStrengthHalf);
  for (int y = half_rows; y < latent.height - half_rows; ++y) {
    bool strong = true;
    for (int k = -reach; k <= reach && strong; ++k)
      strong = strength[static_cast<std::size_t>(y + k)] >= strongest / 2;
    across[static_cast<std::size_t>(y)] = strong;
  }
  return across;
}

Image sum_along_bars(const Image& electrons, const BarSlope& slope, int half_rows) {
  Image out;
  const int rows = 2 * half_rows + 1;
  for (const Plane& plane : electrons.channels) {
    Plane sums = Plane::uninitialised(plane.width, plane.height);
    for (int y = 0; y < plane.height; ++y) {
      const std::span<float> row = sums.row(y);
      const int count = sum_row(plane, y, slope, half_rows, 0, row);
      const float scale = static_cast<float>(rows) / static_cast<float>(count);
      if (count != rows)
        for (float& v : row) v *= scale;
    }
    out.channels.push_back(std::move(sums));
  }
  return out;
}

CaptureModel model_of_row_sums(CaptureModel model, int rows) {
  const double n = rows;
  for (double& e : model.led_electrons) e *= n;
  for (double& e : model.ambient_electrons) e *= n;
  model.full_well *= n;
  model.read_noise *= std::sqrt(n);
  model.gain *= std::sqrt(n);
  return model;
}

}  // namespace flutterscan::imaging
