#pragma once
// From stored pixel values (DN) to what the deblurrer works on: electrons,
// black level removed, linear in light.

#include "imaging/capture_model.hpp"
#include "imaging/image.hpp"

namespace flutterscan::imaging {

/// \brief Electrons per pixel from DN: linearise (sRGB or gamma encodings) on
/// the full scale of the bit depth, subtract the black level, times the gain.
Image dn_to_electrons(const Image& dn, const CaptureModel& model);

/// \brief The sRGB transfer curve's inverse, on values in [0, 1].
double srgb_to_linear(double encoded);

/// \brief The sRGB transfer curve (linear light to encoded), on values in [0, 1].
double linear_to_srgb(double linear);

}  // namespace flutterscan::imaging
