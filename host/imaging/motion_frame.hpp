#pragma once
// Every imaging stage works on rows along which the scene moved toward larger
// index (+x): the motion frame. A camera frame is turned into it once, at the
// entry of the per-frame pipeline (MotionFrame), every stage (blur estimate,
// motion refinement, model choice, deblur, guards) reads that one copy, and
// the result is turned back once (MotionFrame::to_camera). The free functions
// below are the turning itself, for the simulator and the Bayer path, whose
// planes start in other geometries.

#include <string>

#include <utility>

#include "flutterscan/common/result.hpp"
#include "imaging/capture_model.hpp"
#include "imaging/image.hpp"
#include "imaging/image_checks.hpp"
#include "imaging/row_levels.hpp"

namespace flutterscan::imaging {

/// \brief `plane` rearranged so the motion runs along rows toward larger x
/// (+x: as is; -x: rows reversed; +y: transposed; -y: transposed and reversed).
Plane to_motion_frame(const Plane& plane, Direction direction);

/// \brief The inverse of to_motion_frame.
Plane from_motion_frame(const Plane& plane, Direction direction);

/// \brief Pixels along the motion in a `width` x `height` camera frame.
inline int length_along_motion(Direction direction, int width, int height) {
  return moves_along_x(direction) ? width : height;
}

/// \brief Position along the motion of camera pixel (x, y) in a `width` x
/// `height` frame, mirrored for -x and -y so that objects move toward larger
/// values (the column of that pixel in the motion frame).
double position_along_motion(Direction direction, double x, double y, int width, int height);

/// \brief The camera's (x, y) of motion-frame sample `n` of line `line`, for a
/// motion frame `along` samples long: the inverse of to_motion_frame's arrangement.
template <typename T>
std::pair<T, T> camera_point(Direction direction, T n, T line, int along) {
  switch (direction) {
    case Direction::kPlusX:
      return {n, line};
    case Direction::kMinusX:
      return {along - 1 - n, line};
    case Direction::kPlusY:
      return {line, n};
    case Direction::kMinusY:
      return {line, along - 1 - n};
  }
  return {n, line};
}

/// \brief A camera frame's channels in the motion frame, made once per frame
/// and checked then (image_checks.hpp: every stage may rely on planes of one
/// size, finite values within range). +x frames are moved in without a copy.
class MotionFrame {
 public:
  MotionFrame() = default;  ///< no channel (what a failed make() holds)
  /// \brief `camera` (planes as the camera delivered them) turned for
  /// `direction`; fails naming what is wrong with the image (image_problem,
  /// which reads every value unless `values` says they were shown in range).
  /// `levels`: the camera planes' row levels when the caller made them (the
  /// session's conversion does, capture/frame_pixels.hpp), adopted for +x frames
  /// whose size they fit; otherwise they are made here, after the turn.
  static Result<MotionFrame, std::string> make(Image camera, Direction direction,
                                               PixelValues values = PixelValues::kScan,
                                               RowLevels levels = {});

  /// \brief The channels in the motion frame: row y, sample n = position n along the motion.
  const Image& image() const { return image_; }
  const Plane& channel(int c) const { return image_.channels[static_cast<std::size_t>(c)]; }
  int channel_count() const { return image_.channel_count(); }
  /// \brief Samples along the motion (the motion frame's width).
  int along() const { return image_.width(); }
  /// \brief Lines along the motion (the motion frame's height).
  int lines() const { return image_.height(); }
  Direction direction() const { return direction_; }
  /// \brief Every row's level in every channel (row_levels.hpp).
  const RowLevels& row_levels() const { return levels_; }

  /// \brief `plane`, made in this motion frame, in the camera's orientation.
  Plane to_camera(const Plane& plane) const { return from_motion_frame(plane, direction_); }

 private:
  MotionFrame(Image camera, Direction direction, RowLevels levels);

  Image image_;
  RowLevels levels_;
  Direction direction_ = Direction::kPlusX;
};

}  // namespace flutterscan::imaging
