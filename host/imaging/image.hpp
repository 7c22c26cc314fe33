#pragma once
// Planar float images: the imaging code's currency. Pure data, no I/O.

#include <algorithm>
#include <cstddef>
#include <memory>
#include <new>
#include <span>
#include <utility>
#include <vector>

namespace flutterscan::imaging {

/// \brief std::allocator, except that a sample made without a value is left
/// unset (default-initialised) instead of zeroed: a plane whose every sample is
/// written next skips a pass over its memory (Plane::uninitialised).
template <typename T>
struct DefaultInitAllocator : std::allocator<T> {
  template <typename U>
  struct rebind {
    using other = DefaultInitAllocator<U>;
  };
  DefaultInitAllocator() = default;
  template <typename U>
  DefaultInitAllocator(const DefaultInitAllocator<U>&) noexcept {}
  template <typename U>
  void construct(U* p) noexcept {
    ::new (static_cast<void*>(p)) U;
  }
  template <typename U, typename... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};

/// \brief A plane's samples.
using Samples = std::vector<float, DefaultInitAllocator<float>>;

/// \brief One channel of float samples, rows contiguous.
struct Plane {
  int width = 0;
  int height = 0;
  Samples pixels;

  Plane() = default;
  /// \brief Every sample `value`.
  Plane(int w, int h, float value = 0.0f)
      : width(w),
        height(h),
        pixels(static_cast<std::size_t>(w) * static_cast<std::size_t>(h), value) {}
  /// \brief Samples not set: for a plane the caller writes whole before it reads it.
  static Plane uninitialised(int w, int h) {
    Plane p;
    p.width = w;
    p.height = h;
    p.pixels = Samples(static_cast<std::size_t>(w) * static_cast<std::size_t>(h));
    return p;
  }

  float& at(int x, int y) { return pixels[static_cast<std::size_t>(y) * width + x]; }
  float at(int x, int y) const { return pixels[static_cast<std::size_t>(y) * width + x]; }
  std::span<float> row(int y) {
    return {pixels.data() + static_cast<std::size_t>(y) * width, static_cast<std::size_t>(width)};
  }
  std::span<const float> row(int y) const {
    return {pixels.data() + static_cast<std::size_t>(y) * width, static_cast<std::size_t>(width)};
  }
  bool empty() const { return pixels.empty(); }
  /// \brief Columns [x0, x1) of rows [y0, y1) (within the plane), copied.
  Plane part(int x0, int y0, int x1, int y1) const {
    Plane out = uninitialised(x1 - x0, y1 - y0);
    for (int y = y0; y < y1; ++y)
      std::copy_n(row(y).begin() + x0, x1 - x0, out.row(y - y0).begin());
    return out;
  }
};

/// \brief A multi-channel image as planes of equal size (channel 0 = red for RGB).
struct Image {
  std::vector<Plane> channels;
  int width() const { return channels.empty() ? 0 : channels[0].width; }
  int height() const { return channels.empty() ? 0 : channels[0].height; }
  int channel_count() const { return static_cast<int>(channels.size()); }
};

}  // namespace flutterscan::imaging
