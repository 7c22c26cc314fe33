#include "imaging/metrics.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace flutterscan::imaging {
namespace {

float clip01(float v) {
  return std::clamp(v, 0.0f, 1.0f);
}

/// Separable Gaussian blur (sigma 1.5, radius 5), edges clamped.
Plane gaussian(const Plane& in) {
  constexpr int kRadius = 5;
  constexpr double kSigma = 1.5;
  double weights[2 * kRadius + 1];
  double total = 0;
  for (int i = -kRadius; i <= kRadius; ++i)
    total += weights[i + kRadius] = std::exp(-i * i / (2 * kSigma * kSigma));
  for (double& w : weights) w /= total;
  Plane across(in.width, in.height);
  for (int y = 0; y < in.height; ++y)
    for (int x = 0; x < in.width; ++x) {
      double sum = 0;
      for (int i = -kRadius; i <= kRadius; ++i)
        sum += weights[i + kRadius] * in.at(std::clamp(x + i, 0, in.width - 1), y);
      across.at(x, y) = static_cast<float>(sum);
    }
  Plane out(in.width, in.height);
  for (int y = 0; y < in.height; ++y)
    for (int x = 0; x < in.width; ++x) {
      double sum = 0;
      for (int i = -kRadius; i <= kRadius; ++i)
        sum += weights[i + kRadius] * across.at(x, std::clamp(y + i, 0, in.height - 1));
      out.at(x, y) = static_cast<float>(sum);
    }
  return out;
}

Plane map(const Plane& a, const Plane& b, auto op) {
  Plane out(a.width, a.height);
  for (std::size_t i = 0; i < a.pixels.size(); ++i) out.pixels[i] = op(a.pixels[i], b.pixels[i]);
  return out;
}

}  // namespace

Region scored_region(int width, int height, double blur_px, Direction direction) {
  const int along = static_cast<int>(std::ceil(blur_px));
  constexpr int kAcross = 8;
  const bool along_x = moves_along_x(direction);
  Region r;
  r.x0 = along_x ? along : kAcross;
  r.x1 = width - (along_x ? along : kAcross);
  r.y0 = along_x ? kAcross : along;
  r.y1 = height - (along_x ? kAcross : along);
  r.x1 = std::max(r.x1, r.x0);
  r.y1 = std::max(r.y1, r.y0);
  return r;
}

double psnr(const Plane& truth, const Plane& estimate, const Region& region) {
  double sum = 0;
  long long count = 0;
  for (int y = region.y0; y < region.y1; ++y)
    for (int x = region.x0; x < region.x1; ++x) {
      const double d = clip01(estimate.at(x, y)) - truth.at(x, y);
      sum += d * d;
      ++count;
    }
  if (count == 0) return 0;
  const double mse = sum / static_cast<double>(count);
  return mse > 0 ? 10.0 * std::log10(1.0 / mse) : 200.0;
}

double ssim(const Plane& truth, const Plane& estimate, const Region& region) {
  Plane e = estimate;
  for (float& v : e.pixels) v = clip01(v);
  const Plane mu_t = gaussian(truth);
  const Plane mu_e = gaussian(e);
  const Plane tt = gaussian(map(truth, truth, [](float a, float b) { return a * b; }));
  const Plane ee = gaussian(map(e, e, [](float a, float b) { return a * b; }));
  const Plane te = gaussian(map(truth, e, [](float a, float b) { return a * b; }));
  constexpr double c1 = 0.01 * 0.01;
  constexpr double c2 = 0.03 * 0.03;
  double sum = 0;
  long long count = 0;
  for (int y = region.y0; y < region.y1; ++y)
    for (int x = region.x0; x < region.x1; ++x) {
      const double mt = mu_t.at(x, y), me = mu_e.at(x, y);
      const double vt = tt.at(x, y) - mt * mt, ve = ee.at(x, y) - me * me;
      const double cov = te.at(x, y) - mt * me;
      sum += ((2 * mt * me + c1) * (2 * cov + c2)) / ((mt * mt + me * me + c1) * (vt + ve + c2));
      ++count;
    }
  return count > 0 ? sum / static_cast<double>(count) : 0.0;
}

}  // namespace flutterscan::imaging
