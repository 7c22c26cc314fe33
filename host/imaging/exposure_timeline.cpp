#include "imaging/exposure_timeline.hpp"

#include <algorithm>
#include <cmath>

namespace flutterscan::imaging {
namespace {

void trim_trailing_zeros(std::vector<double>& taps) {
  while (taps.size() > 1 && taps.back() == 0.0) taps.pop_back();
}

double timeline_end(std::span<const ExposureSegment> segments) {
  double end = 0;
  for (const auto& s : segments) end = std::max(end, s.start_px + s.width_px);
  return end;
}

/// Light per whole slot of `mask` in channel c (crosstalk x LED electrons), or,
/// with `only_led` >= 0, LED only_led's own light with no crosstalk.
double mask_weight(const CaptureModel& m, std::uint8_t mask, int channel, int only_led) {
  double weight = 0;
  for (int k = 0; k < m.code.leds(); ++k) {
    if (!((mask >> k) & 1U)) continue;
    const int led = m.led_of_bit[static_cast<std::size_t>(k)];
    if (only_led >= 0) {
      if (led == only_led) weight += m.led_electrons[static_cast<std::size_t>(led)];
      continue;
    }
    weight += m.crosstalk[static_cast<std::size_t>(channel * m.leds + led)] *
              m.led_electrons[static_cast<std::size_t>(led)];
  }
  return weight;
}

std::vector<double> timeline_psf(const CaptureModel& m, int channel, int only_led,
                                 std::span<const ExposureSegment> segments) {
  std::vector<double> taps(pixel_model_taps(timeline_end(segments), m.pixel_model), 0.0);
  const double ambient_per_slot =
      only_led < 0 ? m.ambient_electrons[static_cast<std::size_t>(channel)] / m.code.length() : 0;
  for (const auto& s : segments) {
    const double weight =
        s.slot_fraction * (mask_weight(m, s.mask, channel, only_led) + ambient_per_slot);
    if (weight > 0) deposit_slot(taps, s.start_px, s.width_px, weight, m.pixel_model);
  }
  trim_trailing_zeros(taps);
  return taps;
}

}  // namespace

std::vector<ExposureSegment> slot_segments(const CaptureModel& model) {
  return segments_from_boundaries(model.code, slot_edges(model));
}

std::vector<ExposureSegment> segments_from_boundaries(const LedCode& code,
                                                      std::span<const double> boundaries) {
  std::vector<ExposureSegment> segments;
  for (int t = 0; t < code.length() && t + 1 < static_cast<int>(boundaries.size()); ++t) {
    const auto i = static_cast<std::size_t>(t);
    segments.push_back(
        {boundaries[i], std::max(0.0, boundaries[i + 1] - boundaries[i]), code.mask(t), 1.0});
  }
  return segments;
}

std::vector<ExposureSegment> cyclic_phase_segments(const CaptureModel& model, double phase_slots) {
  const int length = model.code.length();
  const double slot_width = model.blur_px / length;
  double phase = std::fmod(phase_slots, static_cast<double>(length));
  if (phase < 0) phase += length;
  // Pattern time runs from phase to phase + L; pattern slot j covers [j, j + 1).
  std::vector<ExposureSegment> segments;
  const int first = static_cast<int>(std::floor(phase));
  for (int j = first; j < first + length + 1; ++j) {
    const double lo = std::max(static_cast<double>(j), phase);
    const double hi = std::min(static_cast<double>(j + 1), phase + length);
    if (hi - lo <= 1e-12) continue;
    const std::uint8_t mask = model.code.mask(j % length);
    segments.push_back({(lo - phase) * slot_width, (hi - lo) * slot_width, mask, hi - lo});
  }
  return segments;
}

std::vector<double> timeline_channel_psf(const CaptureModel& model, int channel,
                                         std::span<const ExposureSegment> segments) {
  return timeline_psf(model, channel, -1, segments);
}

std::vector<std::vector<double>> timeline_channel_psfs(const CaptureModel& model,
                                                       std::span<const ExposureSegment> segments) {
  const auto channels = static_cast<std::size_t>(model.channels);
  const std::size_t length = pixel_model_taps(timeline_end(segments), model.pixel_model);
  std::vector<std::vector<double>> out(channels, std::vector<double>(length, 0.0));
  std::vector<double> shape(length, 0.0), weights(channels);
  for (const auto& s : segments) {
    bool lit = false;
    for (std::size_t c = 0; c < channels; ++c) {
      const int channel = static_cast<int>(c);
      const double ambient_per_slot = model.ambient_electrons[c] / model.code.length();
      weights[c] = s.slot_fraction * (mask_weight(model, s.mask, channel, -1) + ambient_per_slot);
      lit = lit || weights[c] > 0;
    }
    if (!lit) continue;
    deposit_slot(shape, s.start_px, s.width_px, 1.0, model.pixel_model);
    // Both pixel models lay a segment on [floor(start), floor(end) + 1] at most.
    const auto first =
        std::min(length - 1, static_cast<std::size_t>(std::max(0.0, std::floor(s.start_px))));
    const std::size_t stop =
        std::min(length - 1,
                 static_cast<std::size_t>(std::max(0.0, std::floor(s.start_px + s.width_px))) + 1);
    for (std::size_t j = first; j <= stop; ++j) {
      for (std::size_t c = 0; c < channels; ++c)
        if (weights[c] > 0) out[c][j] += weights[c] * shape[j];
      shape[j] = 0;
    }
  }
  for (auto& taps : out) trim_trailing_zeros(taps);
  return out;
}

std::vector<double> timeline_led_psf(const CaptureModel& model, int led,
                                     std::span<const ExposureSegment> segments) {
  return timeline_psf(model, 0, led, segments);
}

}  // namespace flutterscan::imaging
