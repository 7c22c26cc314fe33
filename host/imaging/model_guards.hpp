#pragma once
// Guards that flag frames where the capture model does not fit, so the session
// can say so per frame (session.jsonl) and count them (summary.json), instead
// of passing off a bad reconstruction as a read:
// - saturation: samples at the sensor's or the ADC's ceiling (the model is
//   linear; clipped edges deconvolve into ringing);
// - misfit: the latent image, blurred again through each channel's PSF, leaves
//   a residual much larger than the noise model predicts (wrong blur length or
//   direction, a colour object under the grey model, a crosstalk change, a
//   rolling shutter under the global model);
// - blur disagreement: the blur estimated from the frame and the one the
//   encoder gives differ by more than the estimate's confidence allows.

#include <string>
#include <vector>

#include "imaging/blur_estimate.hpp"
#include "imaging/capture_model.hpp"
#include "imaging/image.hpp"
#include "imaging/motion_frame.hpp"

namespace flutterscan::imaging {

/// \brief Flag a frame when more than this share of its samples is saturated.
inline constexpr double kSaturationGuardShare = 0.001;
/// \brief Flag a frame when its residual exceeds the predicted noise variance this many times.
inline constexpr double kMisfitGuardRatio = 3.0;

/// \brief The DN from which a sample counts as saturated: the full well (in DN
/// above the black level) or the largest code of the bit depth, whichever is
/// lower, less half a code.
double saturation_ceiling_dn(const CaptureModel& model);

/// \brief Share of samples of `dn` at or above saturation_ceiling_dn().
double saturated_share(const Image& dn, const CaptureModel& model);

/// \brief Mean squared residual of `frame` against `latent` (in the same motion
/// frame) blurred through each channel's PSF, over the samples whose PSF lies
/// inside the frame, divided by the noise variance the model predicts there.
/// About 1 or less when the model fits; infinite when the sizes differ or the
/// PSF is longer than the frame. Uses every `row_step`-th line along the motion.
double residual_ratio(const MotionFrame& frame, const Plane& latent, const CaptureModel& model,
                      int row_step = 4);

/// \brief True when `encoder_blur_px` lies outside the estimate's confidence:
/// more than max(4 standard errors, 2% of the blur, 0.5 px) away. An estimate
/// without confidence (infinite standard error) never disagrees.
bool blur_disagrees(double encoder_blur_px, const BlurEstimate& estimate);

/// \brief The guards of one frame.
struct GuardReport {
  double saturated_share = 0;
  double residual_ratio = 0;
  bool blur_checked = false;  ///< an estimate was compared with the encoder
  bool blur_disagrees = false;

  bool saturated() const { return saturated_share > kSaturationGuardShare; }
  bool misfit() const { return residual_ratio > kMisfitGuardRatio; }
  /// \brief The names of the guards that fired ("saturated", "misfit", "blur-disagrees").
  std::vector<std::string> flags() const;
};

}  // namespace flutterscan::imaging
