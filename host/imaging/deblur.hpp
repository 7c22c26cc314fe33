#pragma once
// Deblurring and fusion: from a frame's channels (electrons, black level
// removed, linear) and its capture model to one grey latent image
// (reflectance, white = 1), by the method asked for.

#include <optional>
#include <string>
#include <vector>

#include "flutterscan/common/result.hpp"
#include "imaging/capture_model.hpp"
#include "imaging/image.hpp"

namespace flutterscan::imaging {

enum class Method { kJointWiener, kWienerAverage, kRichardsonLucy };

/// \brief "joint-wiener", "wiener-avg", "rl".
std::string method_name(Method method);
std::optional<Method> method_from_name(const std::string& name);

/// \brief The latent's expected gradient variance along the motion (reflectance^2):
/// the Wiener prior. Printed labels (black on white, edges every few pixels) give
/// about this; lambda = 1 / it.
inline constexpr double kLabelGradientVariance = 0.05;

struct DeblurOptions {
  Method method = Method::kJointWiener;
  int iterations = 20;            ///< rl
  bool accelerate = true;         ///< rl: Biggs-Andrews
  double damping = 0;             ///< rl: deconvlucy's DAMPAR, in noise sigmas
  double gradient_variance = kLabelGradientVariance;  ///< Wiener prior
  int threads = 2;
};

struct DeblurResult {
  Plane latent;                        ///< reflectance, same size and orientation as the input
  std::vector<double> noise_variance;  ///< per channel, e-^2, at the frame's mean signal
};

/// \brief Deblurs and fuses `electrons` (one plane per camera channel).
Result<DeblurResult, std::string> deblur(const Image& electrons, const CaptureModel& model,
                                         const DeblurOptions& options);

}  // namespace flutterscan::imaging
