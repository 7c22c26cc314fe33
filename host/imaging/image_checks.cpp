#include "imaging/image_checks.hpp"

#include <cmath>
#include <sstream>

#include "imaging/limits.hpp"

namespace flutterscan::imaging {

std::string image_problem(const Image& image, PixelValues values) {
  if (image.channels.empty()) return "the image has no channel";
  const int width = image.channels[0].width, height = image.channels[0].height;
  if (width < 1 || height < 1)
    return "the image is empty (" + std::to_string(width) + " x " + std::to_string(height) + ")";
  if (width > kMaxFrameSidePx || height > kMaxFrameSidePx)
    return "the image (" + std::to_string(width) + " x " + std::to_string(height) +
           ") has a side beyond " + std::to_string(kMaxFrameSidePx) + " px";
  for (std::size_t c = 0; c < image.channels.size(); ++c) {
    const Plane& plane = image.channels[c];
    if (plane.width != width || plane.height != height)
      return "channel " + std::to_string(c) + " is " + std::to_string(plane.width) + " x " +
             std::to_string(plane.height) + ", channel 0 " + std::to_string(width) + " x " +
             std::to_string(height);
    if (plane.pixels.size() != static_cast<std::size_t>(width) * static_cast<std::size_t>(height))
      return "channel " + std::to_string(c) + " holds " + std::to_string(plane.pixels.size()) +
             " pixels, not width x height";
    if (values == PixelValues::kShownInRange) continue;
    // Non-finite or absurd values (a black level of 1e85 in a descriptor) would turn
    // the whole deconvolution into inf and NaN.
    // A branch-free pass first (it vectorises: every frame goes through it), the
    // position only when it finds something.
    const float* pixels = plane.pixels.data();
    const auto count = plane.pixels.size();
    int out_of_range = 0;
#pragma omp simd reduction(| : out_of_range)
    for (std::size_t i = 0; i < count; ++i)
      out_of_range |= !(std::abs(pixels[i]) <= kMaxPixelValue);
    if (out_of_range == 0) continue;
    for (std::size_t i = 0; i < plane.pixels.size(); ++i)
      if (!(std::abs(plane.pixels[i]) <= kMaxPixelValue))
        return "channel " + std::to_string(c) + " has the value " +
               std::to_string(plane.pixels[i]) + " at (" + std::to_string(i % width) + ", " +
               std::to_string(i / width) + "): not a finite number within +-1e15";
  }
  return {};
}

std::string model_scale_problem(const CaptureModel& model) {
  for (double v : model.crosstalk)
    if (!(v <= kMaxCrosstalk))
      return "a crosstalk entry (" + std::to_string(v) + ") is beyond " +
             std::to_string(static_cast<int>(kMaxCrosstalk));
  for (double v : model.crosstalk)
    if (v != 0 && !(std::abs(v) >= kMinCrosstalk)) {
      std::ostringstream text;
      text << "a crosstalk entry (" << v << ") is below " << kMinCrosstalk
           << ": write 0 for a channel that does not see an LED";
      return text.str();
    }
  if (!(model.gain >= 1e-6))  // electrons = DN x gain: a denormal gain makes every pixel 0
    return "the conversion gain (" + std::to_string(model.gain) + " e-/DN) is below 1e-6";
  for (double v : model.led_electrons)  // a lit LED's light must survive float PSFs
    if (v != 0 && !(v >= kMinLitElectrons))
      return "the model's light (" + std::to_string(v) + " e- per slot) is below " +
             std::to_string(kMinLitElectrons) + " e- (0 for an LED that is off)";
  for (const auto* values : {&model.led_electrons, &model.ambient_electrons})
    for (double v : *values)
      if (!(v <= kMaxModelElectrons))
        return "the model's light (" + std::to_string(v) + " e-) is beyond " +
               std::to_string(static_cast<long long>(kMaxModelElectrons)) + " e-";
  return {};
}

std::string blur_fit_problem(double blur_px, int along, int margin, const std::string& what) {
  if (std::isfinite(blur_px) && blur_px >= 0 && blur_px <= kMaxBlurPx &&
      blur_px + margin < static_cast<double>(along))
    return {};
  std::ostringstream text;
  text.precision(15);
  text << what << " (" << blur_px << " px) ";
  if (!std::isfinite(blur_px) || blur_px < 0)
    text << "must be a finite number >= 0";
  else if (blur_px > kMaxBlurPx)
    text << "is beyond the longest blur, " << kMaxBlurPx << " px";
  else
    text << "does not fit the frame along the motion (" << along << " px"
         << (margin > 0 ? ", less " + std::to_string(margin) : std::string()) << ")";
  return text.str();
}

}  // namespace flutterscan::imaging
