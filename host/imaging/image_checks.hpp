#pragma once
// Preconditions the public imaging functions check at their entry, so that a
// hostile frame or model is an error result, never an out-of-bounds access or
// an allocation sized by a wild value (issue 20).

#include <string>

#include "imaging/capture_model.hpp"
#include "imaging/image.hpp"

namespace flutterscan::imaging {

/// \brief Whether image_problem() reads every pixel value, or the caller has
/// shown them finite and within kMaxPixelValue (a conversion whose inputs bound
/// its outputs: frame_to_electrons of integer samples with a finite black level
/// and gain) and only the shape is checked.
enum class PixelValues { kScan, kShownInRange };

/// \brief Why `image` cannot be processed (no channel, an empty plane, planes of
/// different sizes, pixels not width x height, a side beyond kMaxFrameSidePx, a
/// value that is not finite or beyond kMaxPixelValue, unless `values` says the
/// caller has shown them in range); empty if it can.
std::string image_problem(const Image& image, PixelValues values = PixelValues::kScan);

/// \brief Why the model's light scale cannot be computed with (crosstalk entries
/// beyond kMaxCrosstalk or, other than 0, below kMinCrosstalk, LED or ambient electrons beyond
/// kMaxModelElectrons: the PSFs' spectra, squared in float, would overflow to inf and NaN); empty
/// if fine.
std::string model_scale_problem(const CaptureModel& model);

/// \brief Why a blur of `blur_px` does not fit `along` pixels along the motion
/// with `margin` pixels to spare (not finite, negative, beyond kMaxBlurPx, or
/// blur + margin >= along); empty if it fits. `what` names the blur in the message.
std::string blur_fit_problem(double blur_px, int along, int margin, const std::string& what);

}  // namespace flutterscan::imaging
