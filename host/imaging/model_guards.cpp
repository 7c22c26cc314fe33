#include "imaging/model_guards.hpp"

#include <algorithm>
#include <cmath>

#include "imaging/motion_frame.hpp"

namespace flutterscan::imaging {

double saturated_share(const Image& dn, const CaptureModel& model) {
  const double code_ceiling = std::pow(2.0, model.bit_depth) - 1;
  const double well_ceiling = model.black_level + model.full_well / model.gain;
  const double ceiling = std::min(code_ceiling, well_ceiling) - 0.5;
  std::size_t saturated = 0, total = 0;
  for (const auto& plane : dn.channels) {
    for (float v : plane.pixels) saturated += v >= ceiling ? 1 : 0;
    total += plane.pixels.size();
  }
  return total > 0 ? static_cast<double>(saturated) / static_cast<double>(total) : 0;
}

double residual_ratio(const Image& electrons, const Plane& latent, const CaptureModel& model,
                      int row_step) {
  const Plane x = to_motion_frame(latent, model.direction);
  double ratio_sum = 0;
  int channels = 0;
  for (int c = 0; c < electrons.channel_count(); ++c) {
    const Plane y =
        to_motion_frame(electrons.channels[static_cast<std::size_t>(c)], model.direction);
    const auto taps = channel_psf(model, c);
    const int k = static_cast<int>(taps.size());
    if (y.width != x.width || y.height != x.height || k >= y.width) return INFINITY;
    double squares = 0, signal = 0;
    std::size_t samples = 0;
    for (int row = 0; row < y.height; row += std::max(1, row_step)) {
      const auto observed = y.row(row);
      const auto sharp = x.row(row);
      for (int n = k - 1; n < y.width; ++n) {
        double predicted = 0;
        for (int j = 0; j < k; ++j) predicted += taps[static_cast<std::size_t>(j)] * sharp[n - j];
        const double r = observed[n] - predicted;
        squares += r * r;
        signal += observed[n];
        ++samples;
      }
    }
    if (samples == 0) continue;
    const double variance =
        channel_noise_variance(model, std::max(0.0, signal / static_cast<double>(samples)));
    ratio_sum += squares / static_cast<double>(samples) / variance;
    ++channels;
  }
  return channels > 0 ? ratio_sum / channels : 0;
}

bool blur_disagrees(double encoder_blur_px, const BlurEstimate& estimate) {
  if (!std::isfinite(estimate.standard_error_px)) return false;
  const double allowed = std::max({4 * estimate.standard_error_px, 0.02 * estimate.blur_px, 0.5});
  return std::abs(encoder_blur_px - estimate.blur_px) > allowed;
}

std::vector<std::string> GuardReport::flags() const {
  std::vector<std::string> out;
  if (saturated()) out.emplace_back("saturated");
  if (misfit()) out.emplace_back("misfit");
  if (blur_checked && blur_disagrees) out.emplace_back("blur-disagrees");
  return out;
}

}  // namespace flutterscan::imaging
