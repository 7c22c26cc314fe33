#include "sim/pixel_integration.hpp"

#include <algorithm>

namespace flutterscan::sim {

imaging::CaptureModel rendered_pixels(imaging::CaptureModel model) {
  if (model.pixel_model == imaging::PixelModel::kBandLimited)
    model.pixel_model = imaging::PixelModel::kBoxAperture;
  return model;
}

using imaging::Plane;

Plane bin_pixels(const Plane& fine, int k) {
  if (k <= 1) return fine;
  Plane out(fine.width / k, fine.height / k);
  const double scale = 1.0 / (static_cast<double>(k) * k);
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x) {
      double sum = 0;
      for (int dy = 0; dy < k; ++dy)
        for (int dx = 0; dx < k; ++dx) sum += fine.at(x * k + dx, y * k + dy);
      out.at(x, y) = static_cast<float>(sum * scale);
    }
  return out;
}

Plane blur_and_bin_rows(const Plane& fine, const std::vector<double>& fine_taps, int k) {
  k = std::max(k, 1);
  const int width = fine.width / k, height = fine.height / k;
  Plane out(width, height);
  // Polyphase form: with m = k q + r, the binned convolution is
  // y[i] = sum_r sum_q taps[k q + r] B_r[i - q], B_r[n] = mean_p across[k n + p - r],
  // `across` the k fine rows of the output row averaged. k convolutions of the
  // camera's length instead of one k times longer on a k times longer row.
  std::vector<double> across(static_cast<std::size_t>(fine.width));
  std::vector<std::vector<double>> phase(static_cast<std::size_t>(k),
                                         std::vector<double>(static_cast<std::size_t>(width)));
  const auto taps_per_phase = (fine_taps.size() + static_cast<std::size_t>(k) - 1) / k;
  for (int y = 0; y < height; ++y) {
    std::fill(across.begin(), across.end(), 0.0);
    for (int dy = 0; dy < k; ++dy) {
      const auto row = fine.row(y * k + dy);
      for (std::size_t x = 0; x < across.size(); ++x) across[x] += row[x];
    }
    for (double& v : across) v /= k;
    for (int r = 0; r < k; ++r) {
      auto& b = phase[static_cast<std::size_t>(r)];
      for (int n = 0; n < width; ++n) {
        double sum = 0;
        for (int p = 0; p < k; ++p)
          sum += across[static_cast<std::size_t>(std::max(0, k * n + p - r))];
        b[static_cast<std::size_t>(n)] = sum / k;
      }
    }
    auto dst = out.row(y);
    for (int i = 0; i < width; ++i) {
      double sum = 0;
      for (int r = 0; r < k; ++r) {
        const auto& b = phase[static_cast<std::size_t>(r)];
        for (std::size_t q = 0; q < taps_per_phase; ++q) {
          const std::size_t m = q * static_cast<std::size_t>(k) + static_cast<std::size_t>(r);
          if (m >= fine_taps.size()) break;
          sum += fine_taps[m] * b[static_cast<std::size_t>(std::max(0, i - static_cast<int>(q)))];
        }
      }
      dst[static_cast<std::size_t>(i)] = static_cast<float>(sum);
    }
  }
  return out;
}

}  // namespace flutterscan::sim
