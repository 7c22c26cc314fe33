#pragma once
// Accuracy metrics with docs/conventions.md's conventions: latent reflectance with
// white = 1, the estimate clipped to [0, 1], scored over the frame minus a
// border of one blur length along the motion and 8 px across it.

#include "imaging/capture_model.hpp"
#include "imaging/image.hpp"

namespace flutterscan::imaging {

/// \brief The scored region of a frame.
struct Region {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;  ///< half-open
};

/// \brief The frame minus the scoring border (docs/conventions.md) for this blur and direction.
Region scored_region(int width, int height, double blur_px, Direction direction);

/// \brief PSNR in dB of `estimate` (clipped to [0, 1]) against `truth` over `region`.
double psnr(const Plane& truth, const Plane& estimate, const Region& region);

/// \brief Mean SSIM (Gaussian window, sigma 1.5, data range 1) over `region`.
double ssim(const Plane& truth, const Plane& estimate, const Region& region);

}  // namespace flutterscan::imaging
