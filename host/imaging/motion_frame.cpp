#include "imaging/motion_frame.hpp"

#include <algorithm>
#include <utility>

#include "imaging/image_checks.hpp"

namespace flutterscan::imaging {
namespace {

Plane transposed(const Plane& in) {
  Plane out = Plane::uninitialised(in.height, in.width);  // every sample written below
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

Result<MotionFrame, std::string> MotionFrame::make(Image camera, Direction direction,
                                                   PixelValues values, RowLevels levels) {
  using Out = Result<MotionFrame, std::string>;
  if (auto problem = image_problem(camera, values); !problem.empty()) return Out::failure(problem);
  return Out::success(MotionFrame(std::move(camera), direction, std::move(levels)));
}

MotionFrame::MotionFrame(Image camera, Direction direction, RowLevels levels)
    : direction_(direction) {
  if (direction == Direction::kPlusX) {
    image_ = std::move(camera);
  } else {
    for (const Plane& plane : camera.channels)
      image_.channels.push_back(to_motion_frame(plane, direction));
  }
  if (direction == Direction::kPlusX &&
      levels.fits(image_.channel_count(), image_.height(), image_.width()))
    levels_ = std::move(levels);
  else
    levels_ = RowLevels::of(image_);
}

double position_along_motion(Direction direction, double x, double y, int width, int height) {
  switch (direction) {
    case Direction::kPlusX:
      return x;
    case Direction::kMinusX:
      return width - 1 - x;
    case Direction::kPlusY:
      return y;
    case Direction::kMinusY:
      return height - 1 - y;
  }
  return x;
}

}  // namespace flutterscan::imaging
