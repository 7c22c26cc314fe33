#include "imaging/model_choice.hpp"

#include "imaging/blur_estimate.hpp"

#include <algorithm>

namespace flutterscan::imaging {

std::string FrameModelChoice::describe() const {
  return std::string(latent == LatentModel::kGrey ? "grey latent" : "per-channel latents") +
         (per_row_phase ? ", per-row code phase" : ", global code phase") +
         (blur_from_encoder ? ", blur from the encoder" : ", blur estimated from the frame");
}

FrameModelChoice choose_frame_model(const MotionFrame& frame, const CaptureModel& model,
                                    bool rolling_shutter, bool encoder_present) {
  FrameModelChoice choice;
  choice.per_row_phase = rolling_shutter;
  choice.blur_from_encoder = encoder_present;
  if (frame.channel_count() >= 2) {
    // A statistic over the frame: about 32 rows along the motion (over 50,000
    // samples per channel pair at 1080p) measure it as well as all of them (a
    // colour label spans many rows), at a small fraction of the cost.
    const auto residual = cross_channel_residual(frame, model, std::max(1, frame.lines() / 32));
    if (residual.ok()) {
      choice.grey_residual = residual.value();
      if (residual.value() > kColourResidual) choice.latent = LatentModel::kPerChannel;
    }
  }
  return choice;
}

}  // namespace flutterscan::imaging
