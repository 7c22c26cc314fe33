#pragma once
// Raw Bayer RGGB input: splitting the mosaic into its colour planes, a bilinear
// demosaic, and deblurring a mosaic either on its raw planes or after a
// demosaic.
//
// Mosaic layout (sim::record_frame with CaptureModel::bayer_rggb): R at (even x,
// even y), G1 at (odd x, even y), G2 at (even x, odd y), B at (odd x, odd y).
// Every site is a pure sample of one camera channel, so G1 and G2 are both the
// green channel (the green row of the crosstalk matrix).
//
// Raw-plane deblurring (BayerMode::kRawPlanes), in the motion frame (the motion
// runs along rows toward larger index, motion_frame.hpp):
// - Along the motion each colour is sampled every second pixel, so the latent
//   is solved at half resolution along the motion: latent sample m stands for
//   the full-resolution pixel pair {2m, 2m+1} (motion-frame columns), centred
//   on column 2m + 0.5. Full-resolution PSF taps (channel_psf, the simulator's
//   own) are summed in pairs: a half-resolution tap is exactly the light of
//   the motion path over two full-resolution pixels, i.e. the PSF of half the
//   blur.
// - The sites of a pair are one full-resolution pixel (half a latent pixel)
//   apart along the motion. A colour whose sites fall on the first (upstream)
//   pixel of each pair, column 2m, sees the scene one pixel further upstream
//   than one on 2m+1, so its PSF is delayed by one full-resolution pixel
//   before the pairs are summed. Which colours that is depends on the
//   direction: on +x the even-x colours (R, G2), on -x the odd-x ones (G1, B),
//   on +y the even-y ones (R, G1), on -y the odd-y ones (G2, B). The sub-pixel
//   offset is thus modelled exactly, not interpolated.
// - Across the motion there is no blur, so the latent keeps full resolution
//   there: each row of the motion frame carries two colours at their own
//   sites; the two colours of the neighbouring rows are interpolated into it
//   (mean of the row before and after). The four planes R, G1, G2, B are then
//   deblurred jointly (their PSFs differ only by crosstalk row and the delay
//   above), with each plane's noise variance at its mean signal.
// - The half-resolution latent is upsampled along the motion by linear
//   interpolation between the pair centres, so full-resolution pixel (x, y) of
//   the output is the latent at the object's position at the start of slot 0
//   (docs/conventions.md), like deblur()'s. A mosaic with an odd length along the
//   motion is solved without its last column (row) and that pixel repeats its
//   neighbour.
//
// Demosaic-first (BayerMode::kDemosaicFirst): demosaic_bilinear to full RGB,
// then deblur() with the frame's 3-channel model. Interpolated sites carry less
// noise and a smoothed PSF than the model assumes; docs/bayer.md measures both.

#include <optional>
#include <string>

#include "flutterscan/common/result.hpp"
#include "imaging/capture_model.hpp"
#include "imaging/deblur.hpp"
#include "imaging/image.hpp"

namespace flutterscan::imaging {

/// \brief How a Bayer mosaic is deblurred: on its raw colour planes, or demosaicked first.
enum class BayerMode { kRawPlanes, kDemosaicFirst };

/// \brief "raw" or "demosaic".
std::string bayer_mode_name(BayerMode mode);
/// \brief The mode called `name` (see bayer_mode_name), if any.
std::optional<BayerMode> bayer_mode_from_name(const std::string& name);

/// \brief The four colour planes of an RGGB mosaic at half resolution, in the
/// order R, G1 (odd x, even y), G2 (even x, odd y), B; plane pixel (i, j) is the
/// site of its colour in the 2x2 cell (2i, 2j). An odd last column or row is dropped.
Image split_bayer_planes(const Plane& mosaic);

/// \brief Bilinear demosaic of an RGGB mosaic to full-resolution R, G, B: each
/// site keeps its own sample; a missing colour is the mean of the nearest sites
/// of that colour in the 3x3 neighbourhood (2 or 4 of them; fewer at the border).
Image demosaic_bilinear(const Plane& mosaic);

/// \brief deblur_bayer's latent, in the camera's orientation (`latent`, as
/// deblur() of a camera frame gives it) and in the motion frame
/// (`motion_latent`, motion_frame.hpp), where the session looks for labels.
struct BayerDeblurResult : DeblurResult {
  Plane motion_latent;  ///< `latent` in the motion frame: made there, turned back once
};

/// \brief Deblurs a raw RGGB mosaic (electrons, black level removed, linear)
/// into one grey latent of the mosaic's size, registered as deblur()'s.
/// `model` is the frame's 3-channel RGB model (full-resolution blur). The
/// result's noise_variance has one entry per plane deblurred: R, G1, G2, B for
/// kRawPlanes, R, G, B for kDemosaicFirst.
Result<BayerDeblurResult, std::string> deblur_bayer(const Plane& mosaic_electrons,
                                                    const CaptureModel& model,
                                                    const DeblurOptions& options, BayerMode mode);

}  // namespace flutterscan::imaging
