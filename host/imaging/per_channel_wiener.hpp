#pragma once
// The per-channel model for colour objects (only colour objects
// need per-channel unmixing). A colour object has one reflectance per LED
// band, r_k, and channel c records
//   y_c = sum_k M[c][k] (h_k * r_k) + a_c (rect * r_c) + noise,
// so a grey model (one latent seen by every channel) misreads a red print
// that the red channel sees as nearly white. Here the three latents are
// solved jointly per frequency from the three channels: in each bin of a
// row's FFT, with A[c][k] = M[c][k] H_k(w) (+ the ambient box on the
// diagonal) and V = diag(v_c),
//   R(w) = (A^H V^-1 A + lambda P(w) I)^-1 A^H V^-1 Y(w),
// a 3x3 regularised least-squares problem (P(w) = |1 - e^{-iw}|^2, the same
// gradient prior as joint Wiener, on each band). Borders as joint Wiener
// (periodic extension by a raised-cosine blend). The bands are fused to grey
// for decoding by their mean (sim::fuse_bands judges the truth the same way).
// One-of-3 codes pay for it: each band is seen mostly through one LED's code,
// a third of the slots, so its nulls are not covered by the others.

#include <string>
#include <vector>

#include "flutterscan/common/result.hpp"
#include "imaging/capture_model.hpp"
#include "imaging/motion_frame.hpp"
#include "imaging/row_fft.hpp"

namespace flutterscan::imaging {

/// \brief What the bands may be. kThreeBands: three independent latents, as
/// above. kPrintPlane: a label is paper, belt and one ink, three colours that
/// lie in a plane of colour space, so after a first three-band solve the bands'
/// mean colour and two principal colour directions (from the estimate itself)
/// fix r = mean + u1 a1 + u2 a2, and a second solve finds the two latents a1,
/// a2 from the three channels: fewer unknowns per bin than data, so one
/// channel's good frequencies cover another's nulls, as in the grey model.
enum class ColourPrior { kThreeBands, kPrintPlane };

/// \brief What deblur_per_channel() returns: the bands and their mean, or the
/// mean alone (what decoding reads; one inverse transform a row instead of one
/// a band).
enum class PerChannelOutput { kBands, kGreyOnly };

struct PerChannelResult {
  std::vector<Plane> bands;  ///< reflectance under each LED (LED 0 first); none for kGreyOnly
  Plane grey;                ///< mean of the bands, for decoding and scoring
  std::vector<double> noise_variance;  ///< per channel, e-^2, at the frame's mean signal
};

struct PerChannelOptions {
  int threads = 2;
  ColourPrior prior = ColourPrior::kThreeBands;
  PerChannelOutput output = PerChannelOutput::kBands;
  PlanEffort plan_effort = PlanEffort::kEstimate;  ///< FFTW planning (row_fft.hpp)
};

/// \brief Deblurs `frame` (electrons, 3 channels, black level removed, linear)
/// into one latent per LED band, in the motion frame. Needs 3 channels and 3 LEDs; `lambda` weights
/// the gradient prior of every band (1 / kLabelGradientVariance in deblur()).
Result<PerChannelResult, std::string> deblur_per_channel(const MotionFrame& frame,
                                                         const CaptureModel& model, double lambda,
                                                         const PerChannelOptions& options = {});

}  // namespace flutterscan::imaging
