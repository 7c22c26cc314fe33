#pragma once
// The forward model of docs/conventions.md: a grey scene (reflectance) moving under
// coded LED light, seen through the camera's channels with crosstalk and
// ambient light, and recorded with EMVA 1288 noise.

#include <cstdint>

#include "imaging/capture_model.hpp"
#include "imaging/image.hpp"

namespace flutterscan::sim {

/// \brief Expected electrons per channel (no noise) of a scene rendered
/// `supersample` times finer than the camera's pixels (render_scene): the
/// model's PSF on that fine grid along the motion, then each block binned into
/// one pixel (sim/pixel_integration.hpp). Scene content upstream of the frame
/// edge repeats the edge pixels (the belt continues). With supersample 1 the
/// scene is taken as constant over each pixel.
imaging::Image expected_electrons(const imaging::Plane& reflectance,
                                  const imaging::CaptureModel& model, int supersample = 1);

/// \brief One recorded frame in DN (integer-valued floats): Poisson shot noise,
/// Gaussian read noise, saturation at the full well, DN = e / gain + black
/// level, rounded and clipped to the bit depth, then encoded (sRGB or gamma)
/// if the model says so. Deterministic for a given seed. A Bayer model gives
/// one plane holding the RGGB mosaic.
imaging::Image record_frame(const imaging::Image& expected, const imaging::CaptureModel& model,
                            std::uint64_t seed);

}  // namespace flutterscan::sim
