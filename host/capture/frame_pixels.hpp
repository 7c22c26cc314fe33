#pragma once
// From a captured frame's bytes to planar DN values, the imaging code's input.

#include <string>

#include "capture/camera_source.hpp"
#include "flutterscan/common/result.hpp"
#include "imaging/capture_model.hpp"
#include "imaging/image.hpp"
#include "imaging/image_checks.hpp"
#include "imaging/row_levels.hpp"

namespace flutterscan::capture {

/// \brief The frame's samples as stored (DN), one plane per channel in R, G, B
/// order (one plane for mono and for a Bayer mosaic). YUYV is converted to RGB
/// with BT.601 and MJPEG decoded, both mixing the channels (warned at start).
/// The error names the frame and what is inconsistent (size, data length).
Result<imaging::Image, std::string> frame_to_dn(const Frame& frame);

/// \brief A frame as the workers deblur it.
struct ElectronFrame {
  imaging::Image electrons;    ///< imaging::dn_to_electrons(frame_to_dn(frame), model)
  double saturated_share = 0;  ///< imaging::saturated_share(frame_to_dn(frame), model)
  /// kShownInRange when the samples' range, the black level and the gain bound every
  /// value within imaging::kMaxPixelValue (the one-pass conversion with a finite black
  /// level and gain): imaging::MotionFrame::make need not read them again.
  imaging::PixelValues values = imaging::PixelValues::kScan;
  /// The rows' levels (imaging/row_levels.hpp), made by the one-pass conversion of
  /// RGB and mono frames while each row is in cache (empty otherwise: Bayer mosaics,
  /// the three-step path): imaging::MotionFrame::make adopts them.
  imaging::RowLevels levels;
};

/// \brief frame_to_dn, imaging::saturated_share and imaging::dn_to_electrons,
/// with the same results; in one pass over the samples for linear RGB8/BGR8/
/// RGB16, mono and Bayer frames (the session's per-frame path), else in three.
Result<ElectronFrame, std::string> frame_to_electrons(const Frame& frame,
                                                      const imaging::CaptureModel& model);

}  // namespace flutterscan::capture
