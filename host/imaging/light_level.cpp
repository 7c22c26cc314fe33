#include "imaging/light_level.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "imaging/frame_conversion.hpp"

namespace flutterscan::imaging {
namespace {

using Out = Result<LightLevel, std::string>;

/// The channels' electrons summed, box-smoothed over (2r + 1)^2 pixels; only
/// pixels whose whole box is inside the frame (the rest are left at -inf).
Plane smoothed_grey(const Image& electrons, int r) {
  const int w = electrons.width(), h = electrons.height();
  // Summed-area table of the grey, (w + 1) x (h + 1), in double.
  std::vector<double> table(static_cast<std::size_t>(w + 1) * (h + 1), 0.0);
  auto at = [&](int x, int y) -> double& {
    return table[static_cast<std::size_t>(y) * (w + 1) + x];
  };
  for (int y = 0; y < h; ++y) {
    double row = 0;
    for (int x = 0; x < w; ++x) {
      for (const Plane& p : electrons.channels) row += p.at(x, y);
      at(x + 1, y + 1) = at(x + 1, y) + row;
    }
  }
  Plane out(w, h, -INFINITY);
  const double area = static_cast<double>((2 * r + 1) * (2 * r + 1));
  for (int y = r; y + r < h; ++y)
    for (int x = r; x + r < w; ++x) {
      const double sum =
          at(x + r + 1, y + r + 1) - at(x - r, y + r + 1) - at(x + r + 1, y - r) + at(x - r, y - r);
      out.at(x, y) = static_cast<float>(sum / area);
    }
  return out;
}

std::string number(double value) {
  std::ostringstream text;
  text.precision(4);
  text << value;
  return text.str();
}

}  // namespace

CaptureModel unit_light_model(const CaptureModel& camera, const LedCode& probe, double cap) {
  CaptureModel m = camera;
  m.code = probe;
  m.blur_px = 0;
  const std::vector<double> per_bit = budgeted_led_electrons(probe, 1.0, cap);
  m.led_electrons.assign(static_cast<std::size_t>(m.leds), 0.0);
  for (std::size_t k = 0; k < per_bit.size(); ++k) {
    const auto led = static_cast<std::size_t>(m.led_of_bit[k]);
    if (led < m.led_electrons.size()) m.led_electrons[led] = per_bit[k];
  }
  m.ambient_electrons.assign(static_cast<std::size_t>(m.channels), 0.0);
  return m;
}

Out estimate_light_level(const std::vector<Image>& dn_frames, const CaptureModel& unit,
                         const LightLevelOptions& options) {
  if (dn_frames.empty()) return Out::failure("no frames");
  const int w = dn_frames.front().width(), h = dn_frames.front().height();
  const int channels = dn_frames.front().channel_count();
  const int r = std::max(0, options.smooth_radius_px);
  if (channels != unit.channels)
    return Out::failure("frames have " + std::to_string(channels) + " channels, the model " +
                        std::to_string(unit.channels));
  for (const Image& f : dn_frames)
    if (f.width() != w || f.height() != h || f.channel_count() != channels)
      return Out::failure("frames of different sizes");
  if (w <= 2 * r || h <= 2 * r) return Out::failure("frames smaller than the smoothing box");
  if (!(options.paper_reflectance > 0 && options.paper_reflectance <= 1))
    return Out::failure("paper reflectance must be within (0, 1]");

  LightLevel level;
  level.frames = static_cast<int>(dn_frames.size());
  for (int c = 0; c < channels; ++c) level.white_per_unit_e += channel_white_electrons(unit, c);
  if (!(level.white_per_unit_e > 0))
    return Out::failure("the probe lights nothing the camera sees (white per unit E is 0)");

  std::vector<Plane> grey;
  std::vector<float> values;
  for (const Image& f : dn_frames) {
    grey.push_back(smoothed_grey(dn_to_electrons(f, unit), r));
    for (float v : grey.back().pixels)
      if (std::isfinite(v)) values.push_back(v);
  }
  if (values.empty()) return Out::failure("no pixels inside the smoothing box");
  std::vector<float> sorted = values;
  const auto median_at = sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2);
  std::nth_element(sorted.begin(), median_at, sorted.end());
  level.background_electrons = *median_at;
  const double q = std::clamp(options.start_quantile, 0.5, 1.0);
  const auto start_at =
      sorted.begin() +
      static_cast<std::ptrdiff_t>(std::floor(q * static_cast<double>(sorted.size() - 1)));
  std::nth_element(sorted.begin(), start_at, sorted.end());

  // Noise of the smoothed grey at a level: shot, read and quantisation noise of
  // each channel, averaged over the box.
  const double box = static_cast<double>((2 * r + 1) * (2 * r + 1));
  auto smoothed_sigma = [&](double grey_level) {
    return std::sqrt((std::max(0.0, grey_level) +
                      channels * (unit.read_noise * unit.read_noise + unit.gain * unit.gain / 12)) /
                     box);
  };
  auto half_window = [&](double m) { return std::max(0.04 * std::abs(m), 4 * smoothed_sigma(m)); };
  // Mean shift from the start quantile to the brightest plateau.
  double m = *start_at;
  std::size_t count = 0;
  for (int iteration = 0; iteration < 50; ++iteration) {
    const double half = half_window(m);
    double sum = 0;
    count = 0;
    for (float v : values)
      if (std::abs(v - m) <= half) {
        sum += v;
        ++count;
      }
    if (count == 0) break;
    const double next = sum / static_cast<double>(count);
    const bool settled = std::abs(next - m) <= 1e-4 * std::max(1.0, std::abs(m));
    m = next;
    if (settled) break;
  }
  level.paper_electrons = m;
  level.pixels = count;
  if (!(m > 0) || m / smoothed_sigma(m) < options.min_snr)
    return Out::failure("no lit paper: the brightest surface gives " + number(m) + " e- over " +
                        std::to_string(channels) +
                        " channels, within the noise (is the light on, the black level right?)");
  if (count < options.min_pixels)
    return Out::failure("no bright paper: the brightest plateau has " + std::to_string(count) +
                        " pixels over " + std::to_string(dn_frames.size()) + " frames (at least " +
                        std::to_string(options.min_pixels) + " needed: is a label in view?)");

  // Saturation: a channel of the plateau's pixels at the DN ceiling or the full well.
  const double full_scale = std::pow(2.0, unit.bit_depth) - 1;
  const double half = half_window(m);
  std::size_t saturated = 0;
  for (std::size_t i = 0; i < grey.size(); ++i)
    for (std::size_t p = 0; p < grey[i].pixels.size(); ++p) {
      const float v = grey[i].pixels[p];
      if (!std::isfinite(v) || std::abs(v - m) > half) continue;
      for (const Plane& plane : dn_frames[i].channels) {
        const double dn = plane.pixels[p];
        if (dn >= full_scale - 0.5 ||
            (dn - unit.black_level) * unit.gain >= 0.99 * unit.full_well) {
          ++saturated;
          break;
        }
      }
    }
  level.saturated_share = static_cast<double>(saturated) / static_cast<double>(count);
  if (level.saturated_share > options.max_saturated)
    return Out::failure(
        "the brightest paper saturates (" + number(100 * level.saturated_share) +
        "% of its pixels at full scale): the probe needs less light per exposure or a "
        "lower camera gain");
  level.electrons = m / (options.paper_reflectance * level.white_per_unit_e);
  return Out::success(level);
}

}  // namespace flutterscan::imaging
