#include "imaging/frame_conversion.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace flutterscan::imaging {

double srgb_to_linear(double v) {
  return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
}

Image dn_to_electrons(const Image& dn, const CaptureModel& m) {
  const double full_scale = std::pow(2.0, m.bit_depth) - 1.0;
  Image out;
  for (const Plane& plane : dn.channels) {
    Plane e(plane.width, plane.height);
    for (std::size_t i = 0; i < plane.pixels.size(); ++i) {
      double value = plane.pixels[i];
      if (m.encoding != Encoding::kLinear) {
        const double unit = std::clamp(value / full_scale, 0.0, 1.0);
        value = full_scale *
                (m.encoding == Encoding::kSrgb ? srgb_to_linear(unit) : std::pow(unit, m.gamma));
      }
      e.pixels[i] = static_cast<float>((value - m.black_level) * m.gain);
    }
    out.channels.push_back(std::move(e));
  }
  return out;
}

}  // namespace flutterscan::imaging
