#pragma once
// One frame through the simplest model that fits it (model no more
// than a scene needs; docs/algorithms.md), and the guards that say when no model
// fits: the session's worker calls this instead of deblurring directly.
//
// Per frame:
// 1. blur: from the encoder when the line has one, refined on the frame within
//    +-blur_tolerance of it (imaging/motion_refinement.hpp: also a speed change
//    within the exposure when the data ask for it); a frame without edges
//    along the motion keeps the encoder's blur, and a refinement on the edge of
//    the tolerance ("blur-off-encoder") or with a residual that says the grey
//    model does not fit ("motion-unfit") is flagged and not used. Otherwise estimated from
//    the frame itself (imaging/blur_estimate.hpp) within -20%..+25% of the
//    nominal blur, from about 90 rows; a frame without edges along the motion
//    keeps the fallback (the last confident estimate) and is flagged
//    "blur-unknown";
// 2. model: grey latent unless the cross-channel residual says colour print
//    (imaging/model_choice.hpp), then per-channel latents (Wiener); a
//    rolling-shutter camera gets a per-row code phase;
// 3. guards (imaging/model_guards.hpp): saturated share, residual against
//    the noise model (grey global model only), and every `blur_check_every`
//    frames the estimated blur against the encoder's.
// The frame's log gets "model" (what was chosen and why) and "guards"; the
// guard names that fired are returned as flags for session.jsonl.

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "flutterscan/common/result.hpp"
#include "imaging/capture_model.hpp"
#include "imaging/deblur.hpp"
#include "imaging/image.hpp"
#include "imaging/motion_frame.hpp"
#include "imaging/motion_refinement.hpp"

namespace flutterscan::session {

/// \brief How a line is set up, as far as the model choice is concerned.
struct ModelFitConfig {
  bool encoder = true;           ///< the blur comes from the encoder
  bool choose_latent = true;     ///< test each frame for colour print
  double line_time_us = 0;       ///< > 0: rolling-shutter camera, per-row code phase
  double slot_time_us = 100;     ///< the controller's slot time (for the row phases)
  int blur_check_every = 0;      ///< > 0: estimate the blur every N frames and compare
  double blur_tolerance = 0.10;  ///< with an encoder: refine within +-this fraction (0: off)
  /// > 0 (with refinement on): the session is behind, so the frame is not
  /// refined; the encoder's blur is scaled by this instead (the latest refined
  /// frame's refined / encoder blur, or 1), and the frame flagged "motion-reused".
  double reuse_motion_ratio = 0;
  /// Without an encoder: the blur to use when a frame gives no confident
  /// estimate (the session passes the last confident one; 0: the nominal blur).
  double fallback_blur_px = 0;
};

struct FittedFrame {
  imaging::Plane latent;           ///< grey reflectance, in the motion frame
  std::vector<std::string> flags;  ///< guards that fired
  nlohmann::json log;              ///< {"model": ..., "guards": ...}
  double estimated_blur_px = 0;    ///< a confident estimate from this frame (0: none)
  /// With an encoder and refinement on: what the refinement found, and whether
  /// the frame was deblurred with it.
  std::optional<imaging::MotionRefinement> refinement;
  bool refinement_used = false;
  /// The model the latent was deblurred with (the blur and speed the fit chose).
  imaging::CaptureModel model;
  /// The latent is the grey global model's, made by imaging::deblur.
  bool grey_global = false;
  /// The latent is the per-channel model's (colour print), every row under the
  /// code's global timing. Either this or grey_global: the cascade's second
  /// pass can redo the frame window by window with the grey model and tv
  /// (not for per-row code phases).
  bool per_channel = false;
};

/// \brief Deblurs one frame (`frame`: electrons in the motion frame;
/// `saturated_share` of its samples at the ceiling, imaging::saturated_share)
/// under the simplest model that fits.
/// `model.blur_px` is the nominal (encoder) blur; `frame_index` paces the blur
/// check. Fails only when deblurring itself fails.
Result<FittedFrame, std::string> deblur_fitting_model(
    double saturated_share, const imaging::MotionFrame& frame, imaging::CaptureModel model,
    const imaging::DeblurOptions& options, const ModelFitConfig& config, std::uint64_t frame_index);

}  // namespace flutterscan::session
