#pragma once
// From a captured frame's bytes to planar DN values, the imaging code's input.

#include <string>

#include "capture/camera_source.hpp"
#include "flutterscan/common/result.hpp"
#include "imaging/image.hpp"

namespace flutterscan::capture {

/// \brief The frame's samples as stored (DN), one plane per channel in R, G, B
/// order (one plane for mono and for a Bayer mosaic). YUYV is converted to RGB
/// with BT.601 and MJPEG decoded, both mixing the channels (warned at start).
/// The error names the frame and what is inconsistent (size, data length).
Result<imaging::Image, std::string> frame_to_dn(const Frame& frame);

}  // namespace flutterscan::capture
