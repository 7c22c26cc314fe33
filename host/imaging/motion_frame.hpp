#pragma once
// Every deblurring method works on rows along which the scene moved toward
// larger index (+x). These functions turn a plane into that frame and back.

#include "imaging/capture_model.hpp"
#include "imaging/image.hpp"

#include <vector>

namespace flutterscan::imaging {

/// \brief `plane` rearranged so the motion runs along rows toward larger x
/// (+x: as is; -x: rows reversed; +y: transposed; -y: transposed and reversed).
Plane to_motion_frame(const Plane& plane, Direction direction);

/// \brief Rows of to_motion_frame(plane, direction): lines along the motion.
int motion_rows(const Plane& plane, Direction direction);

/// \brief Row `row` of to_motion_frame(plane, direction), into `out` (resized),
/// without rearranging the whole plane: for checks that sample a few rows.
void motion_row(const Plane& plane, Direction direction, int row, std::vector<float>& out);

/// \brief The inverse of to_motion_frame.
Plane from_motion_frame(const Plane& plane, Direction direction);

}  // namespace flutterscan::imaging
