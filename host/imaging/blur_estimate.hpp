#pragma once
// The blur length of a coded frame from the frame itself, for lines without an
// encoder (and to check the encoder on lines with one). One parameter: the code,
// the crosstalk and the direction are known; only the motion during the
// exposure is not.
//
// Principle (cross-channel consistency): every channel sees the same grey
// scene x through its own PSF, y_c = h_c * x + noise. For the true blur,
// h_d * y_c - h_c * y_d = h_d * h_c * x - h_c * h_d * x + noise = noise, for
// every pair of channels, whatever the scene. For a wrong blur the scene's
// edges leave a residual. So the estimate minimises
//   R(b) = sum over pairs, rows and valid samples of e_cd^2 / var(e_cd),
//   e_cd = h_d(b) * y_c - h_c(b) * y_d,
// var(e_cd) = v_c |h_d|^2 + v_d |h_c|^2 (white noise), which is about 1 per
// sample at the true blur. Only samples whose convolutions lie wholly inside
// the row count ("valid" part), so the frame's borders do not bias it. The
// convolutions are products of zero-padded row FFTs.
// It needs channels whose codes differ (a one-of-3 triplet); a frame lit by
// one code on every channel (white flutter, rect, a mono camera) carries no
// blur information this way and is refused.
//
// Confidence: a sandwich (robust) standard error over 16 blocks of rows,
// sqrt(sum_k R_k'(b)^2) / sum_k R_k''(b) at the estimate, R_k the residual of
// block k: blocks without edges add neither slope nor curvature. That local
// measure cannot see a frame that has no edges at all (its residual is noise,
// nearly flat in b, with random shallow minima), so a frame whose median
// residual over the search range is less than 10% above the minimum
// (contrast < 0.1) gets an infinite standard error: no estimate.

#include <string>

#include "flutterscan/common/result.hpp"
#include "imaging/capture_model.hpp"
#include "imaging/motion_frame.hpp"

namespace flutterscan::imaging {

struct BlurEstimate {
  double blur_px = 0;            ///< the estimate
  double standard_error_px = 0;  ///< sandwich estimate over row blocks
  /// How much worse a typical blur in the range explains the frame: the median
  /// residual over the search grid / the residual at the estimate - 1.
  double contrast = 0;
  double residual_per_sample = 0;  ///< R / samples at the estimate: ~1 if the model fits
};

/// \brief Estimates the blur of `frame` (electrons, one plane per channel, black
/// level removed) between min_px and max_px from every `row_step`-th line along
/// the motion; `model` gives everything else (its blur_px is ignored). Fails for
/// fewer than two channels, channels that share one code, or a range that does
/// not fit the frame.
Result<BlurEstimate, std::string> estimate_blur(const MotionFrame& frame, const CaptureModel& model,
                                                double min_px, double max_px, int row_step = 1);

/// \brief The cross-channel residual per sample (R / samples above) at the
/// model's own blur, over every `row_step`-th row along the motion: about 1
/// when the frame fits a grey scene under `model`; much more when it does not
/// (colour objects, a wrong blur, a changed crosstalk). Fails as estimate_blur does.
Result<double, std::string> cross_channel_residual(const MotionFrame& frame,
                                                   const CaptureModel& model, int row_step = 1);

}  // namespace flutterscan::imaging
