#pragma once
// Planar float images: the imaging code's currency. Pure data, no I/O.

#include <cstddef>
#include <span>
#include <vector>

namespace flutterscan::imaging {

/// \brief One channel of float samples, rows contiguous.
struct Plane {
  int width = 0;
  int height = 0;
  std::vector<float> pixels;

  Plane() = default;
  Plane(int w, int h, float value = 0.0f)
      : width(w),
        height(h),
        pixels(static_cast<std::size_t>(w) * static_cast<std::size_t>(h), value) {}

  float& at(int x, int y) { return pixels[static_cast<std::size_t>(y) * width + x]; }
  float at(int x, int y) const { return pixels[static_cast<std::size_t>(y) * width + x]; }
  std::span<float> row(int y) {
    return {pixels.data() + static_cast<std::size_t>(y) * width, static_cast<std::size_t>(width)};
  }
  std::span<const float> row(int y) const {
    return {pixels.data() + static_cast<std::size_t>(y) * width, static_cast<std::size_t>(width)};
  }
  bool empty() const { return pixels.empty(); }
};

/// \brief A multi-channel image as planes of equal size (channel 0 = red for RGB).
struct Image {
  std::vector<Plane> channels;
  int width() const { return channels.empty() ? 0 : channels[0].width; }
  int height() const { return channels.empty() ? 0 : channels[0].height; }
  int channel_count() const { return static_cast<int>(channels.size()); }
};

}  // namespace flutterscan::imaging
