#include "imaging/frame_conversion.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace flutterscan::imaging {

double srgb_to_linear(double v) {
  return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
}

double linear_to_srgb(double v) {
  return v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055;
}

Image dn_to_electrons(const Image& dn, const CaptureModel& m) {
  const double full_scale = std::pow(2.0, m.bit_depth) - 1.0;
  Image out;
  for (const Plane& plane : dn.channels) {
    Plane e(plane.width, plane.height);
    const std::size_t count = plane.pixels.size();
    const float* __restrict in = plane.pixels.data();
    float* __restrict to = e.pixels.data();
    if (m.encoding == Encoding::kLinear) {
      // The common case, in float (vectorised): (DN - black) x gain.
      const auto black = static_cast<float>(m.black_level);
      const auto gain = static_cast<float>(m.gain);
      for (std::size_t i = 0; i < count; ++i) to[i] = (in[i] - black) * gain;
    } else {
      for (std::size_t i = 0; i < count; ++i) {
        const double unit = std::clamp(in[i] / full_scale, 0.0, 1.0);
        const double value = full_scale * (m.encoding == Encoding::kSrgb ? srgb_to_linear(unit)
                                                                         : std::pow(unit, m.gamma));
        to[i] = static_cast<float>((value - m.black_level) * m.gain);
      }
    }
    out.channels.push_back(std::move(e));
  }
  return out;
}

}  // namespace flutterscan::imaging
