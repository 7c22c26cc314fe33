#pragma once
// The camera's pixels integrating a scene that moves continuously: the
// simulator renders a scene `k` times finer than the camera's pixels in both
// directions, blurs it along the motion on that fine grid, and averages each
// k x k block into one pixel (a box aperture). The scene then moves
// continuously within each camera pixel while a slot is lit, whatever model
// of the pixels the deblurring assumes (imaging/motion_psf.hpp).

#include <vector>

#include "imaging/capture_model.hpp"
#include "imaging/image.hpp"

namespace flutterscan::sim {

/// \brief How much finer than the camera's pixels the simulator renders
/// scenes by default.
inline constexpr int kSimSupersample = 4;

/// \brief `model` as the simulator renders it: its pixels are boxes over a
/// scene rendered finer, so a band-limited pixel model (the deblur's view of a
/// peer's frames) renders as the box aperture; any other model as it is.
imaging::CaptureModel rendered_pixels(imaging::CaptureModel model);

/// \brief The camera's sharp view of a scene rendered `k` times finer: the
/// mean of each k x k block (width and height divided by k, rounded down).
imaging::Plane bin_pixels(const imaging::Plane& fine, int k);

/// \brief Rows of `fine` (already in the motion frame, k times finer than the
/// camera's pixels) convolved with `fine_taps` (a PSF on the fine grid) along
/// each row, with the scene upstream of the left edge repeating the edge, then
/// binned k x k: y[i] = mean over the block of sum_j taps[j] fine[n - j].
imaging::Plane blur_and_bin_rows(const imaging::Plane& fine, const std::vector<double>& fine_taps,
                                 int k);

}  // namespace flutterscan::sim
