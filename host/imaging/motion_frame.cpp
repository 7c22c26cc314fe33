#include "imaging/motion_frame.hpp"

#include <algorithm>

namespace flutterscan::imaging {
namespace {

Plane transposed(const Plane& in) {
  Plane out(in.height, in.width);
  constexpr int kBlock = 32;
  for (int y0 = 0; y0 < in.height; y0 += kBlock)
    for (int x0 = 0; x0 < in.width; x0 += kBlock)
      for (int y = y0; y < std::min(in.height, y0 + kBlock); ++y)
        for (int x = x0; x < std::min(in.width, x0 + kBlock); ++x) out.at(y, x) = in.at(x, y);
  return out;
}

Plane rows_reversed(Plane plane) {
  for (int y = 0; y < plane.height; ++y) {
    auto row = plane.row(y);
    std::reverse(row.begin(), row.end());
  }
  return plane;
}

}  // namespace

Plane to_motion_frame(const Plane& plane, Direction direction) {
  switch (direction) {
    case Direction::kPlusX:
      return plane;
    case Direction::kMinusX:
      return rows_reversed(plane);
    case Direction::kPlusY:
      return transposed(plane);
    case Direction::kMinusY:
      return rows_reversed(transposed(plane));
  }
  return plane;
}

int motion_rows(const Plane& plane, Direction direction) {
  const bool along_x = direction == Direction::kPlusX || direction == Direction::kMinusX;
  return along_x ? plane.height : plane.width;
}

void motion_row(const Plane& plane, Direction direction, int row, std::vector<float>& out) {
  const bool along_x = direction == Direction::kPlusX || direction == Direction::kMinusX;
  if (along_x) {
    const auto from = plane.row(row);
    out.assign(from.begin(), from.end());
  } else {
    out.resize(static_cast<std::size_t>(plane.height));
    for (int n = 0; n < plane.height; ++n) out[static_cast<std::size_t>(n)] = plane.at(row, n);
  }
  if (direction == Direction::kMinusX || direction == Direction::kMinusY)
    std::reverse(out.begin(), out.end());
}

Plane from_motion_frame(const Plane& plane, Direction direction) {
  switch (direction) {
    case Direction::kPlusX:
      return plane;
    case Direction::kMinusX:
      return rows_reversed(plane);
    case Direction::kPlusY:
      return transposed(plane);
    case Direction::kMinusY:
      return transposed(rows_reversed(plane));
  }
  return plane;
}

}  // namespace flutterscan::imaging
