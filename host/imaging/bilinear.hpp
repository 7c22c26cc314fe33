#pragma once
// A plane's value between its samples: the reader's one sampler (scan lines,
// quiet zones, symbol grids, the bar-pattern fit's profiles).

#include "imaging/image.hpp"

#include <algorithm>
#include <optional>

namespace flutterscan::imaging {

/// \brief The value at (x, y), interpolated bilinearly between the four nearest
/// samples; nullopt off the plane (x outside [0, width - 1], y outside
/// [0, height - 1], or either NaN). The value itself is not clamped: a
/// deblurred latent overshoots, and a caller that wants a reflectance in
/// [0, 1] clamps it. A plane one sample wide (high) interpolates along y (x) only.
inline std::optional<double> bilinear(const Plane& p, double x, double y) {
  if (!(x >= 0 && y >= 0 && x <= p.width - 1 && y <= p.height - 1)) return std::nullopt;
  const int x0 = std::min(static_cast<int>(x), std::max(p.width - 2, 0));
  const int y0 = std::min(static_cast<int>(y), std::max(p.height - 2, 0));
  const int x1 = std::min(x0 + 1, p.width - 1), y1 = std::min(y0 + 1, p.height - 1);
  const double fx = x - x0, fy = y - y0;
  const double top = p.at(x0, y0) * (1 - fx) + p.at(x1, y0) * fx;
  const double bottom = p.at(x0, y1) * (1 - fx) + p.at(x1, y1) * fx;
  return top * (1 - fy) + bottom * fy;
}

}  // namespace flutterscan::imaging
