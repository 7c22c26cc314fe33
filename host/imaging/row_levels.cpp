#include "imaging/row_levels.hpp"

#include <algorithm>
#include <cmath>

#include "imaging/lane_sum.hpp"

namespace flutterscan::imaging {

RowLevel row_level(std::span<const float> row) {
  const std::size_t n = row.size();
  RowLevel level;
  if (n < 2) return level;
  const float* samples = row.data();
  level.sum = lane_sum(n, [&](std::size_t x) { return samples[x]; });
  const float mean = level.mean(n);
  const std::size_t stretches = std::max<std::size_t>(1, n / kFlatRowStretch);
  const std::size_t shortest = n / stretches;
  for (std::size_t k = 0; k < stretches; ++k) {
    const std::size_t from = k * shortest, to = k + 1 == stretches ? n : from + shortest;
    const float* part = samples + from;
    const float squares = lane_sum(to - from, [&](std::size_t x) {
      const float d = part[x] - mean;
      return d * d;
    });
    // A NaN (from a non-finite sample) stays: no threshold passes it.
    const double mean_square = squares / static_cast<double>(to - from);
    if (k == 0 || std::isnan(mean_square) || mean_square > level.worst_mean_square)
      level.worst_mean_square = mean_square;
  }
  return level;
}

RowLevels::RowLevels(int channels, int rows, int width)
    : channels_(channels),
      rows_(rows),
      width_(width),
      levels_(static_cast<std::size_t>(channels) * static_cast<std::size_t>(rows)) {}

RowLevels RowLevels::of(const Image& image) {
  RowLevels levels(image.channel_count(), image.height(), image.width());
  for (int c = 0; c < image.channel_count(); ++c) {
    const Plane& plane = image.channels[static_cast<std::size_t>(c)];
    for (int y = 0; y < plane.height; ++y) levels.set(c, y, row_level(plane.row(y)));
  }
  return levels;
}

double RowLevels::mean_of_rows(int channel, int step) const {
  double sum = 0;
  std::size_t count = 0;
  for (int y = 0; y < rows_; y += step) {
    sum += at(channel, y).sum;
    count += static_cast<std::size_t>(width_);
  }
  return count == 0 ? 0.0 : sum / static_cast<double>(count);
}

}  // namespace flutterscan::imaging
