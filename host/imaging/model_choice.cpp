#include "imaging/model_choice.hpp"

#include "imaging/blur_estimate.hpp"

namespace flutterscan::imaging {

std::string FrameModelChoice::describe() const {
  return std::string(latent == LatentModel::kGrey ? "grey latent" : "per-channel latents") +
         (per_row_phase ? ", per-row code phase" : ", global code phase") +
         (blur_from_encoder ? ", blur from the encoder" : ", blur estimated from the frame");
}

FrameModelChoice choose_frame_model(const Image& electrons, const CaptureModel& model,
                                    bool rolling_shutter, bool encoder_present) {
  FrameModelChoice choice;
  choice.per_row_phase = rolling_shutter;
  choice.blur_from_encoder = encoder_present;
  if (electrons.channel_count() >= 2) {
    const auto residual = cross_channel_residual(electrons, model);
    if (residual.ok()) {
      choice.grey_residual = residual.value();
      if (residual.value() > kColourResidual) choice.latent = LatentModel::kPerChannel;
    }
  }
  return choice;
}

}  // namespace flutterscan::imaging
