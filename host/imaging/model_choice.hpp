#pragma once
// Model no more than the scene needs (docs/algorithms.md): per frame, the simplest
// model that fits, and a record of which was chosen.
// - latent: one grey latent image, unless the frame does not fit a grey scene
//   (colour print): then one latent per LED band (per-channel unmixing). The
//   test is the cross-channel residual at the frame's blur
//   (blur_estimate.hpp): about 1 for a grey scene, far above for colour.
// - code phase: global, unless the camera is configured as rolling shutter:
//   then per row.
// - blur: from the encoder when there is one, else estimated from the frame.

#include <string>

#include "imaging/capture_model.hpp"
#include "imaging/motion_frame.hpp"

namespace flutterscan::imaging {

/// \brief Above this cross-channel residual (per sample, in units of the noise)
/// a frame is taken not to be a grey scene.
inline constexpr double kColourResidual = 4.0;

enum class LatentModel { kGrey, kPerChannel };

struct FrameModelChoice {
  LatentModel latent = LatentModel::kGrey;
  bool per_row_phase = false;
  bool blur_from_encoder = true;
  double grey_residual = 0;  ///< cross-channel residual per sample (0 if not measured)
  /// \brief e.g. "grey latent, global code phase, blur from the encoder".
  std::string describe() const;
};

/// \brief Chooses the model of one frame (electrons, black level removed; `model`
/// with the blur in use). A frame with one channel, or whose channels share one
/// code shape, keeps the grey model (the test needs different codes).
FrameModelChoice choose_frame_model(const MotionFrame& frame, const CaptureModel& model,
                                    bool rolling_shutter, bool encoder_present);

}  // namespace flutterscan::imaging
