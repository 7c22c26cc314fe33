#include "imaging/model_guards.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "imaging/lane_sum.hpp"

namespace flutterscan::imaging {

double saturation_ceiling_dn(const CaptureModel& model) {
  const double code_ceiling = std::pow(2.0, model.bit_depth) - 1;
  const double well_ceiling = model.black_level + model.full_well / model.gain;
  return std::min(code_ceiling, well_ceiling) - 0.5;
}

double saturated_share(const Image& dn, const CaptureModel& model) {
  const double ceiling = saturation_ceiling_dn(model);
  std::size_t saturated = 0, total = 0;
  for (const auto& plane : dn.channels) {
    for (float v : plane.pixels) saturated += v >= ceiling ? 1 : 0;
    total += plane.pixels.size();
  }
  return total > 0 ? static_cast<double>(saturated) / static_cast<double>(total) : 0;
}

double residual_ratio(const MotionFrame& frame, const Plane& latent, const CaptureModel& model,
                      int row_step) {
  double ratio_sum = 0;
  int channels = 0;
  std::vector<float> predicted;
  if (frame.along() != latent.width || frame.lines() != latent.height) return INFINITY;
  const int width = frame.along();
  // Tap j of a PSF with a lead moves the latent j - lead pixels downstream.
  const int lead = pixel_model_lead(model.pixel_model);
  for (int c = 0; c < frame.channel_count(); ++c) {
    const Plane& plane = frame.channel(c);
    const auto psf = channel_psf(model, c);
    const std::vector<float> taps(psf.begin(), psf.end());
    const int k = static_cast<int>(taps.size());
    if (k >= width || lead >= k) return INFINITY;
    double squares = 0, signal = 0;
    std::size_t samples = 0;
    for (int row = 0; row < frame.lines(); row += std::max(1, row_step)) {
      const auto observed = plane.row(row);
      const auto sharp = latent.row(row);
      // The blurred row, tap by tap over the whole row (vectorises): sample n
      // sees latent n - j + lead through tap j, valid from n = k - 1 - lead.
      predicted.assign(static_cast<std::size_t>(width), 0.0f);
      for (int j = 0; j < k; ++j) {
        const float tap = taps[static_cast<std::size_t>(j)];
        for (int n = k - 1 - lead; n < width - lead; ++n) predicted[n] += tap * sharp[n - j + lead];
      }
      const float* seen = observed.data() + (k - 1 - lead);
      const float* blurred = predicted.data() + (k - 1 - lead);
      const auto valid = static_cast<std::size_t>(width - k + 1);
      squares += lane_sum(valid, [&](std::size_t n) {
        const float r = seen[n] - blurred[n];
        return r * r;
      });
      signal += lane_sum(valid, [&](std::size_t n) { return seen[n]; });
      samples += static_cast<std::size_t>(width - k + 1);
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
