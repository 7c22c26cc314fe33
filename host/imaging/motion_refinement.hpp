#pragma once
// The motion of one frame refined from the frame itself, cheaply enough for
// every frame (docs/algorithms.md, "Motion refinement").
//
// Principle: as imaging/blur_estimate.hpp (cross-channel consistency): every
// channel sees the same grey scene x through its own PSF, so for the true
// motion e_cd = h_d * y_c - h_c * y_d is noise for every pair of channels,
// and for a wrong one the scene's edges leave a residual. Here the rows are
// differenced first (e becomes its difference, still noise at the true
// motion; the flat parts of the frame then carry no weight and the sums keep
// their precision in float FFTs), and the residual over the valid samples of
// the sampled rows is a quadratic form in the taps:
//   sum_n e_cd[n]^2 = h_d' G_cc h_d + h_c' G_dd h_c - 2 h_d' G_cd h_c,
//   G_ab[i][j] = sum over valid n of a[n - i] b[n - j],
// so the rows are read and transformed once per frame, and each candidate
// motion costs a few P x P products (P taps), whatever the frame size. The
// G's come from one FFT cross-correlation per block of rows plus exact
// corrections at the rows' ends.
//
// Per frame: the rows with the most edge energy along the motion (a label's
// rows) are read best first, in batches: 32 rows, then as many more as the
// standard error they gave says bring it below 0.02 px (the error falls as
// 1 / sqrt(rows)), up to MotionRefinementOptions::rows; each batch is added to
// the G's and the search below runs again. A frame that could not show edges
// with every row read (its significance grows at most as sqrt(rows), and falls
// once the rows added carry less edge than those before) stops there, and a
// bright label reads a quarter of the rows. A grid and golden section
// over blur_px within the tolerance find the constant-speed motion; when its residual stays above
// the noise, a two-parameter motion (blur and the end / start speed ratio, constant acceleration)
// is fitted as well and kept only if it explains the frame clearly better; when even that leaves
// the residual above the noise, a speed that wanders from block to block of the exposure (block
// offsets at 7 knots, capture_model.hpp: belt jitter) is fitted on the last batch of rows and
// kept on the same terms, with a clearer gain. Standard errors are
// sandwich estimates over blocks of rows; a frame whose residual hardly depends on the blur (no
// edges along the motion) gets none and keeps the given motion.

#include <string>
#include <vector>

#include "flutterscan/common/result.hpp"
#include "imaging/capture_model.hpp"
#include "imaging/motion_frame.hpp"

namespace flutterscan::imaging {

/// \brief Largest relative tolerance refine_motion() takes (exclusive).
inline constexpr double kMaxBlurTolerance = 1.0;

struct MotionRefinementOptions {
  /// The given blur b is taken as within this share of the true one, either
  /// way it is read: the truth within b (1 - tolerance) .. b / (1 - tolerance)
  /// (searched two slots wider); 0 <= tolerance < 1.
  double tolerance = 0.10;
  int rows = 128;  ///< most rows along the motion to use (the most edgy ones)
  /// Try the two-parameter (accelerating) motion, and then the wandering one.
  bool speed_change = true;
};

struct MotionRefinement {
  double blur_px = 0;            ///< refined (the given value when !edges)
  double standard_error_px = 0;  ///< sandwich over row blocks; infinite when !edges
  double speed_ratio = 1;        ///< end / start speed; 1 unless `accelerating`
  /// Block offsets (CaptureModel::block_offsets_px) on top of that; empty unless `wandering`.
  std::vector<double> block_offsets_px;
  /// Whether the frame constrained the motion: edges along it (a residual that
  /// depends on the blur) and a finite standard error.
  bool edges = false;
  bool accelerating = false;  ///< the two-parameter motion explained the frame better
  bool wandering = false;     ///< the block offsets explained it better still
  /// The encoder's blur is off by more than the tolerance: the refined blur lies
  /// outside given (1 - tolerance) .. given / (1 - tolerance) by more than 3
  /// standard errors, or on the edge of the (two slots wider) search.
  bool outside_tolerance = false;
  double contrast = 0;  ///< median residual over the searched blurs / the best one - 1
  /// How far the best blur stands out: (median - best residual) over the noise
  /// of the residual; edges need 20 or more (a flat frame gives a few).
  double significance = 0;
  double residual_per_sample = 0;      ///< at the refined motion: about 1 when the model fits
  double constant_speed_residual = 0;  ///< at the best constant-speed motion
  int rows_used = 0;
};

/// \brief Whether refine_motion() can search around `model.blur_px` with
/// `tolerance` on a frame `along` pixels long along the motion: the longest PSF searched
/// must leave at least as many valid samples as it has taps.
bool refinement_fits(const CaptureModel& model, double tolerance, int along);

/// \brief Refines the motion of `frame` (electrons, one plane per channel, black
/// level removed) around `model` (its blur_px and speed_ratio are the start;
/// everything else is taken as known). Fails for fewer than two channels,
/// channels that share one code, a tolerance outside [0, 1), or a search
/// range that does not fit the frame along the motion.
Result<MotionRefinement, std::string> refine_motion(const MotionFrame& frame,
                                                    const CaptureModel& model,
                                                    const MotionRefinementOptions& options);

/// \brief Above this residual per sample (about 1 when the grey model fits) a
/// refined motion is not trusted: colour print, or no model fits.
inline constexpr double kUnfitMotionResidual = 3.0;

/// \brief Whether a deblur should take the refined motion: the frame has edges
/// along the motion, the blur is within the tolerance and the model fits
/// (residual <= kUnfitMotionResidual).
bool refinement_usable(const MotionRefinement& refinement);

/// \brief `model` with the motion `refinement` found (blur, speed ratio, block offsets).
CaptureModel with_refined_motion(CaptureModel model, const MotionRefinement& refinement);

/// \brief `model` with its motion refined on `frame` within `tolerance`, where
/// that can be done (tolerance > 0, channels that do not share one code, a
/// search that fits the frame) and the result is usable (refinement_usable());
/// else `model` as it is. For callers that want the deblur's model, not the log.
CaptureModel motion_refined(const MotionFrame& frame, const CaptureModel& model, double tolerance);

}  // namespace flutterscan::imaging
