#include "imaging/capture_model.hpp"

#include "imaging/exposure_timeline.hpp"

#include <algorithm>
#include <cmath>

#include "imaging/lane_sum.hpp"
#include "imaging/limits.hpp"

namespace flutterscan::imaging {
namespace {

bool finite_non_negative(double v) {
  return std::isfinite(v) && v >= 0;
}

}  // namespace

std::string capture_model_problem(const CaptureModel& m) {
  if (m.code.length() == 0) return "the capture has no code";
  if (m.channels != 1 && m.channels != 3) return "channels must be 1 (mono) or 3 (RGB)";
  if (m.leds < 1 || m.leds > kMaxLeds) return "leds must be 1 to 4";
  if (m.code.leds() > m.leds)
    return "the code drives " + std::to_string(m.code.leds()) + " LEDs but the capture has " +
           std::to_string(m.leds);
  for (int k = 0; k < m.code.leds(); ++k)
    if (m.led_of_bit[static_cast<std::size_t>(k)] < 0 ||
        m.led_of_bit[static_cast<std::size_t>(k)] >= m.leds)
      return "led_of_bit[" + std::to_string(k) + "] names no LED";
  if (!std::isfinite(m.blur_px) || m.blur_px < 0) return "blur must be a finite number >= 0 pixels";
  if (m.blur_px > kMaxBlurPx)  // imaging/limits.hpp: the PSF and padded rows grow with it
    return "blur " + std::to_string(m.blur_px) + " px is beyond the longest blur, " +
           std::to_string(static_cast<int>(kMaxBlurPx)) + " px";
  if (!std::isfinite(m.speed_ratio) || m.speed_ratio < kMinSpeedRatio ||
      m.speed_ratio > 1 / kMinSpeedRatio)
    return "the speed ratio (end / start of the exposure) must be between " +
           std::to_string(kMinSpeedRatio) + " and " + std::to_string(1 / kMinSpeedRatio);
  if (static_cast<int>(m.block_offsets_px.size()) >= m.code.length())
    return "the block offsets need fewer entries than the code has slots (" +
           std::to_string(m.code.length()) + ")";
  for (double v : m.block_offsets_px)
    if (!std::isfinite(v)) return "the block offsets must be finite numbers (pixels)";
  if (!m.block_offsets_px.empty() && !edges_move_forward(slot_edges(m)))
    return "the block offsets make the object move backwards within the exposure";
  if (m.crosstalk.size() != static_cast<std::size_t>(m.channels * m.leds))
    return "the crosstalk matrix must have " + std::to_string(m.channels) + " rows of " +
           std::to_string(m.leds) + " entries";
  for (double v : m.crosstalk)
    if (!finite_non_negative(v)) return "crosstalk entries must be finite and >= 0";
  if (m.led_electrons.size() != static_cast<std::size_t>(m.leds))
    return "led_electrons needs one value per LED";
  for (double v : m.led_electrons)
    if (!finite_non_negative(v)) return "led_electrons must be finite and >= 0";
  if (m.ambient_electrons.size() != static_cast<std::size_t>(m.channels))
    return "ambient_electrons needs one value per channel";
  for (double v : m.ambient_electrons)
    if (!finite_non_negative(v)) return "ambient_electrons must be finite and >= 0";
  if (!finite_non_negative(m.black_level)) return "black level must be finite and >= 0";
  if (!std::isfinite(m.gain) || m.gain <= 0) return "gain must be a finite number > 0 (e-/DN)";
  if (!finite_non_negative(m.read_noise)) return "read noise must be finite and >= 0";
  if (!std::isfinite(m.full_well) || m.full_well <= 0) return "full well must be finite and > 0";
  if (m.bit_depth < 1 || m.bit_depth > 16) return "bit depth must be 1 to 16";
  if (!std::isfinite(m.gamma) || m.gamma <= 0) return "gamma must be finite and > 0";
  if (m.bayer_rggb && m.channels != 3) return "a Bayer mosaic needs 3 channels";
  if (m.bayer_rggb && m.pixel_model == PixelModel::kBandLimited)
    return "a Bayer mosaic takes the box-aperture or tap-grid pixel model, not band-limited";
  return {};
}

std::vector<double> budgeted_led_electrons(const LedCode& code, double electrons, double cap) {
  std::vector<double> intensity(static_cast<std::size_t>(code.leds()), 0.0);
  const double peak = cap * electrons / code.length();
  for (int k = 0; k < code.leds(); ++k) {
    const int n = code.on_slots(k);
    if (n > 0) intensity[static_cast<std::size_t>(k)] = std::min(electrons / n, peak);
  }
  return intensity;
}

std::vector<double> slot_edges(const CaptureModel& m) {
  auto edges = accelerating_slot_edges(m.code.length(), m.blur_px, m.speed_ratio);
  add_block_offsets(edges, m.block_offsets_px);
  return edges;
}

std::vector<double> channel_psf(const CaptureModel& m, int channel) {
  return timeline_channel_psf(m, channel, slot_segments(m));
}

bool channels_share_one_code(const CaptureModel& model) {
  std::vector<std::vector<double>> shapes;
  for (int c = 0; c < model.channels; ++c) {
    auto taps = channel_psf(model, c);
    double total = 0;
    for (double t : taps) total += t;
    if (total > 0)
      for (double& t : taps) t /= total;
    shapes.push_back(std::move(taps));
  }
  for (std::size_t c = 1; c < shapes.size(); ++c) {
    if (shapes[c].size() != shapes[0].size()) return false;
    for (std::size_t i = 0; i < shapes[c].size(); ++i)
      if (std::abs(shapes[c][i] - shapes[0][i]) > 1e-9) return false;
  }
  return true;
}

double channel_white_electrons(const CaptureModel& m, int channel) {
  double total = 0;
  for (double tap : channel_psf(m, channel)) total += tap;
  return total;
}

double channel_noise_variance(const CaptureModel& m, double signal_electrons) {
  return std::max(0.0, signal_electrons) + m.read_noise * m.read_noise + m.gain * m.gain / 12.0;
}

double noise_level_mean(const Plane& plane) {
  constexpr int kRowStep = kNoiseLevelRowStep;
  double sum = 0;
  std::size_t count = 0;
  for (int y = 0; y < plane.height; y += kRowStep) {
    const float* row = plane.row(y).data();
    // A row in float (vectorised), the rows in double.
    sum += lane_sum(static_cast<std::size_t>(plane.width), [&](std::size_t x) { return row[x]; });
    count += static_cast<std::size_t>(plane.width);
  }
  return count == 0 ? 0.0 : sum / static_cast<double>(count);
}

}  // namespace flutterscan::imaging
