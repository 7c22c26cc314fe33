#include "imaging/bar_sums.hpp"

#include <algorithm>
#include <cmath>
#include <span>
#include <vector>

namespace flutterscan::imaging {
namespace {

/// Adds `row` shifted by `shift` pixels (sample x takes the row at x + shift,
/// linearly interpolated, clamped to the row's ends) into `sum`.
void add_shifted(std::span<const float> row, double shift, std::span<float> sum) {
  const int width = static_cast<int>(row.size());
  const int whole = static_cast<int>(std::floor(shift));
  const auto f = static_cast<float>(shift - whole);
  const float g = 1 - f;
  auto sample = [&](int x) { return row[static_cast<std::size_t>(std::clamp(x, 0, width - 1))]; };
  // Where both neighbours lie inside the row: no clamp (the loop vectorises).
  const int inner0 = std::clamp(-whole, 0, width);
  const int inner1 = std::clamp(width - 1 - whole, inner0, width);
  for (int x = 0; x < inner0; ++x) sum[x] += g * sample(x + whole) + f * sample(x + whole + 1);
  const float* from = row.data();
  float* to = sum.data();
  for (int x = inner0; x < inner1; ++x) to[x] += g * from[x + whole] + f * from[x + whole + 1];
  for (int x = inner1; x < width; ++x) sum[x] += g * sample(x + whole) + f * sample(x + whole + 1);
}

/// Row `y` of `plane` summed along `slope` over the rows [y - half_rows,
/// y + half_rows] that exist, into `sum` (zeroed first); returns how many.
int sum_row(const Plane& plane, int y, double slope, int half_rows, std::span<float> sum) {
  std::fill(sum.begin(), sum.end(), 0.0f);
  int count = 0;
  for (int k = -half_rows; k <= half_rows; ++k) {
    if (y + k < 0 || y + k >= plane.height) continue;
    add_shifted(plane.row(y + k), k * slope, sum);
    ++count;
  }
  return count;
}

/// Contrast along the rows kept by summing along `slope`: the sums' squared
/// steps between neighbours, over every 8th row at least half_rows from the
/// ends.
double kept_contrast(const Plane& latent, double slope, int half_rows) {
  constexpr int kRowStep = 8;
  std::vector<float> sum(static_cast<std::size_t>(latent.width));
  double energy = 0;
  for (int y = half_rows; y < latent.height - half_rows; y += kRowStep) {
    sum_row(latent, y, slope, half_rows, sum);
    float rows = 0;
    for (std::size_t x = 1; x < sum.size(); ++x)
      rows += (sum[x] - sum[x - 1]) * (sum[x] - sum[x - 1]);
    energy += rows;
  }
  return energy;
}

}  // namespace

double bar_slope(const Plane& latent, int half_rows) {
  constexpr double kCoarse = 0.05, kFine = 0.01;
  double best = 0, best_contrast = kept_contrast(latent, 0, half_rows);
  auto consider = [&](double slope) {
    const double c = kept_contrast(latent, slope, half_rows);
    if (c > best_contrast) {
      best_contrast = c;
      best = slope;
    }
  };
  const int coarse = static_cast<int>(std::lround(kMaxBarSlope / kCoarse));
  for (int i = -coarse; i <= coarse; ++i)
    if (i != 0) consider(i * kCoarse);
  const double centre = best;
  const int fine = static_cast<int>(std::lround(kCoarse / kFine));
  for (int i = -fine + 1; i < fine; ++i) {
    const double slope = centre + i * kFine;
    if (i != 0 && std::abs(slope) <= kMaxBarSlope + 1e-9) consider(slope);
  }
  return best;
}

Image sum_along_bars(const Image& electrons, double slope, int half_rows) {
  Image out;
  const int rows = 2 * half_rows + 1;
  for (const Plane& plane : electrons.channels) {
    Plane sums = Plane::uninitialised(plane.width, plane.height);
    for (int y = 0; y < plane.height; ++y) {
      const std::span<float> row = sums.row(y);
      const int count = sum_row(plane, y, slope, half_rows, row);
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
