#include "imaging/capture_model.hpp"

#include <algorithm>
#include <cmath>

#include "imaging/limits.hpp"

namespace flutterscan::imaging {
namespace {

bool finite_non_negative(double v) {
  return std::isfinite(v) && v >= 0;
}

/// Adds `weight` spread evenly over [start, start + width) to the taps it overlaps.
void deposit_box(std::vector<double>& taps, double start, double width, double weight) {
  if (width <= 1e-12) {
    const auto j = static_cast<std::size_t>(std::floor(start));
    taps[std::min(j, taps.size() - 1)] += weight;
    return;
  }
  const double end = start + width;
  for (auto j = static_cast<std::size_t>(std::floor(start)); j < taps.size(); ++j) {
    const double lo = std::max(start, static_cast<double>(j));
    const double hi = std::min(end, static_cast<double>(j + 1));
    if (hi <= lo) {
      if (static_cast<double>(j) >= end) break;
      continue;
    }
    taps[j] += weight * (hi - lo) / width;
  }
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

std::vector<double> channel_psf(const CaptureModel& m, int channel) {
  const int length = m.code.length();
  const double slot_width = m.blur_px / length;
  std::vector<double> taps(static_cast<std::size_t>(std::floor(m.blur_px)) + 1, 0.0);
  for (int t = 0; t < length; ++t) {
    double weight = 0;
    for (int k = 0; k < m.code.leds(); ++k) {
      if (!m.code.is_on(t, k)) continue;
      const int led = m.led_of_bit[static_cast<std::size_t>(k)];
      weight += m.crosstalk[static_cast<std::size_t>(channel * m.leds + led)] *
                m.led_electrons[static_cast<std::size_t>(led)];
    }
    if (weight > 0) deposit_box(taps, t * slot_width, slot_width, weight);
  }
  const double ambient = m.ambient_electrons[static_cast<std::size_t>(channel)];
  if (ambient > 0) deposit_box(taps, 0.0, m.blur_px, ambient);
  while (taps.size() > 1 && taps.back() == 0.0) taps.pop_back();
  return taps;
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
  constexpr int kRowStep = 4;
  double sum = 0;
  std::size_t count = 0;
  for (int y = 0; y < plane.height; y += kRowStep) {
    float row_sum = 0;  // a row in float (vectorised), the rows in double
    for (float v : plane.row(y)) row_sum += v;
    sum += row_sum;
    count += static_cast<std::size_t>(plane.width);
  }
  return count == 0 ? 0.0 : sum / static_cast<double>(count);
}

}  // namespace flutterscan::imaging
