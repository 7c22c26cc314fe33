#pragma once
// Deblurring and fusion: from a frame's channels (electrons, black level
// removed, linear) and its capture model to one grey latent image
// (reflectance, white = 1), by the method asked for.

#include <optional>
#include <span>
#include <string>
#include <vector>

#include "flutterscan/common/result.hpp"
#include "imaging/capture_model.hpp"
#include "imaging/image.hpp"
#include "imaging/joint_wiener.hpp"
#include "imaging/motion_frame.hpp"
#include "imaging/total_variation.hpp"

namespace flutterscan::imaging {

enum class Method { kJointWiener, kWienerAverage, kRichardsonLucy, kTotalVariation };

/// \brief "joint-wiener", "wiener-avg", "rl", "tv".
std::string method_name(Method method);
/// \brief The method called `name` (see method_name), if any.
std::optional<Method> method_from_name(const std::string& name);

/// \brief The latent's expected gradient variance along the motion (reflectance^2):
/// the Wiener prior. Printed labels (black on white, edges every few pixels) give
/// about this; lambda = 1 / it (joint Wiener's prior shape: label_prior_power).
inline constexpr double kLabelGradientVariance = 0.05;

/// \brief Iterations of rl when DeblurOptions::iterations is unset.
inline constexpr int kRichardsonLucyIterations = 20;
/// \brief Iterations of tv when DeblurOptions::iterations is unset: the PSNR that 40
/// iterations of the earlier solver reached on the label scenes, or more
/// (docs/benchmarks.md, "tv: exact x-update").
inline constexpr int kTotalVariationIterations = 15;

struct DeblurOptions {
  Method method = Method::kJointWiener;
  /// rl and tv; unset = the method's own default (kRichardsonLucyIterations,
  /// kTotalVariationIterations).
  std::optional<int> iterations;
  bool accelerate = true;                             ///< rl: Biggs-Andrews
  double damping = 0;                                 ///< rl: deconvlucy's DAMPAR, in noise sigmas
  double gradient_variance = kLabelGradientVariance;  ///< Wiener prior (also tv's warm start)
  EdgePrior edge_prior = EdgePrior::kTotalVariation;  ///< tv: |gradient| or L0 (two-tone)
  /// tv (|gradient| prior): kappa, the prior weight per unit of the estimate's noise
  /// (TotalVariationSettings::weight_per_noise).
  double tv_weight_per_noise = TotalVariationSettings{}.weight_per_noise;
  /// tv (|gradient| prior): the weight across the motion over the weight along it
  /// (TotalVariationSettings::across_ratio; 1: isotropic).
  double tv_across_ratio = TotalVariationSettings{}.across_ratio;
  int threads = 2;
  /// joint-wiener and wiener-avg: FFTW planning (row_fft.hpp). A session measures
  /// before it streams and deblurs with kMeasuredIfKnown.
  PlanEffort plan_effort = PlanEffort::kEstimate;
  /// joint-wiener: rows that carry only noise are filled with the latent of a
  /// constant row instead of transformed (JointWiener::skip_flat_rows). A
  /// session does (its belt between labels costs a row's statistics, not four
  /// FFTs); off elsewhere, so offline deblurs and accuracy figures see every row.
  bool skip_flat_rows = false;
};

struct DeblurResult {
  Plane latent;                        ///< reflectance, same size and orientation as the input
  std::vector<double> noise_variance;  ///< per channel, e-^2, at the frame's mean signal
  int flat_rows = 0;                   ///< rows filled as flat (DeblurOptions::skip_flat_rows)
};

/// \brief The method dispatch on rows already in the motion frame: `rows[c]`
/// observed through `psfs[c]`, Wiener prior weight `lambda`. deblur() and the
/// Bayer path call it.
Plane deconvolve_motion_rows(std::span<const ChannelPsf> psfs, std::span<const Plane> rows,
                             double lambda, double read_variance, const DeblurOptions& options);

/// \brief Deblurs and fuses `frame` (electrons, one plane per camera channel,
/// black level removed); the latent is in the motion frame.
Result<DeblurResult, std::string> deblur(const MotionFrame& frame, const CaptureModel& model,
                                         const DeblurOptions& options);

/// \brief deblur() of one camera frame on its own: turned into the motion frame
/// for model.direction, deblurred, the latent turned back. The per-frame
/// pipeline, which runs several stages on one frame, makes the MotionFrame itself.
Result<DeblurResult, std::string> deblur(const Image& electrons, const CaptureModel& model,
                                         const DeblurOptions& options);

}  // namespace flutterscan::imaging
