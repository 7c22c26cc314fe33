#include "imaging/deblur.hpp"

#include <algorithm>
#include <cmath>

#include "imaging/image_checks.hpp"
#include "imaging/joint_wiener.hpp"
#include "imaging/limits.hpp"
#include "imaging/motion_frame.hpp"
#include "imaging/richardson_lucy.hpp"

namespace flutterscan::imaging {

std::string method_name(Method method) {
  switch (method) {
    case Method::kJointWiener:
      return "joint-wiener";
    case Method::kWienerAverage:
      return "wiener-avg";
    case Method::kRichardsonLucy:
      return "rl";
    case Method::kTotalVariation:
      return "tv";
  }
  return "?";
}

std::optional<Method> method_from_name(const std::string& name) {
  for (Method m : {Method::kJointWiener, Method::kWienerAverage, Method::kRichardsonLucy,
                   Method::kTotalVariation})
    if (method_name(m) == name) return m;
  return std::nullopt;
}

Plane deconvolve_motion_rows(std::span<const ChannelPsf> psfs, std::span<const Plane> rows,
                             double lambda, double read_variance, const DeblurOptions& options) {
  const int width = rows[0].width;
  Plane latent;
  switch (options.method) {
    case Method::kJointWiener:
      latent =
          JointWiener(psfs, width, lambda, options.plan_effort).deconvolve(rows, options.threads);
      break;
    case Method::kWienerAverage: {
      int used = 0;
      for (std::size_t c = 0; c < psfs.size(); ++c) {
        double gain = 0;
        for (double tap : psfs[c].taps) gain += tap;
        // A channel no LED reaches carries no image; nor does one that gets less than
        // kMinLitElectrons in all (a crosstalk of 1e-125 from the one lit LED): alone, its
        // Wiener filter is 1 / gain at the DC bin, which the prior leaves alone, and in float
        // that was inf (a fuzz finding, host/fuzz/pipeline/corpus/finding-not-finite-5).
        if (!(gain >= kMinLitElectrons)) continue;
        const Plane one = JointWiener({&psfs[c], 1}, width, lambda, options.plan_effort)
                              .deconvolve({&rows[c], 1}, options.threads);
        if (latent.empty()) latent = Plane(one.width, one.height);
        for (std::size_t i = 0; i < one.pixels.size(); ++i) latent.pixels[i] += one.pixels[i];
        ++used;
      }
      if (used == 0) {  // the entries refuse such a model; never 0 / 0
        latent = Plane(width, rows[0].height);
        break;
      }
      for (float& v : latent.pixels) v /= static_cast<float>(used);
      break;
    }
    case Method::kRichardsonLucy: {
      const RichardsonLucySettings settings{options.iterations.value_or(kRichardsonLucyIterations),
                                            options.accelerate, options.damping};
      latent =
          RichardsonLucy(psfs, width, read_variance, settings).deconvolve(rows, options.threads);
      break;
    }
    case Method::kTotalVariation: {
      // Warm start: the joint Wiener solution with the same prior, made inside
      // the solver from the data spectra it needs anyway (an empty start plane).
      TotalVariationSettings settings =
          options.edge_prior == EdgePrior::kL0Gradient ? l0_settings() : TotalVariationSettings{};
      settings.iterations = options.iterations.value_or(kTotalVariationIterations);
      settings.wiener_lambda = lambda;
      if (options.edge_prior == EdgePrior::kTotalVariation) {
        settings.weight_per_noise = options.tv_weight_per_noise;
        settings.across_ratio = options.tv_across_ratio;
      }
      latent = TotalVariation(psfs, width, settings).deconvolve(rows, Plane(), options.threads);
      break;
    }
  }
  return latent;
}

Result<DeblurResult, std::string> deblur(const MotionFrame& frame, const CaptureModel& model,
                                         const DeblurOptions& options) {
  using Out = Result<DeblurResult, std::string>;
  if (auto problem = capture_model_problem(model); !problem.empty()) return Out::failure(problem);
  if (auto problem = model_scale_problem(model); !problem.empty()) return Out::failure(problem);
  if (frame.channel_count() != model.channels)
    return Out::failure("the frame has " + std::to_string(frame.channel_count()) +
                        " channels but the capture model " + std::to_string(model.channels));
  if (model.blur_px >= frame.along())
    return Out::failure("the blur (" + std::to_string(model.blur_px) +
                        " px) is not shorter than the image along the motion (" +
                        std::to_string(frame.along()) + " px)");
  if (!(options.gradient_variance > 0) || !std::isfinite(options.gradient_variance))
    return Out::failure("the prior gradient variance must be a finite number > 0");
  if (options.iterations && *options.iterations < 1)
    return Out::failure("iterations must be at least 1");

  DeblurResult result;
  const std::span<const Plane> rows(frame.image().channels);
  std::vector<ChannelPsf> psfs;
  for (int c = 0; c < model.channels; ++c) {
    // noise_level_mean(frame.channel(c)), from the rows' levels.
    const double variance =
        channel_noise_variance(model, frame.row_levels().mean_of_rows(c, kNoiseLevelRowStep));
    result.noise_variance.push_back(variance);
    psfs.push_back({channel_psf(model, c), variance});
  }
  double brightest = 0;  // the most light one channel gets, e-
  for (const auto& p : psfs) {
    double gain = 0;
    for (double tap : p.taps) gain += tap;
    brightest = std::max(brightest, gain);
  }
  if (!(brightest >= kMinLitElectrons))
    return Out::failure("the capture model lights no channel: every PSF is zero (or below " +
                        std::to_string(kMinLitElectrons) + " e-)");

  if (options.skip_flat_rows && options.method == Method::kJointWiener) {
    JointWiener wiener(psfs, rows[0].width, 1.0 / options.gradient_variance, options.plan_effort);
    wiener.skip_flat_rows(
        std::vector<double>(psfs.size(), channel_noise_variance(model, 0)));  // without shot noise
    result.latent = wiener.deconvolve(rows, options.threads, &frame.row_levels());
    result.flat_rows = wiener.flat_rows();
  } else {
    result.latent = deconvolve_motion_rows(psfs, rows, 1.0 / options.gradient_variance,
                                           model.read_noise * model.read_noise, options);
  }
  undo_psf_lead(result.latent, pixel_model_lead(model.pixel_model));
  return Out::success(std::move(result));
}

Result<DeblurResult, std::string> deblur(const Image& electrons, const CaptureModel& model,
                                         const DeblurOptions& options) {
  using Out = Result<DeblurResult, std::string>;
  auto frame = MotionFrame::make(electrons, model.direction);
  if (!frame.ok()) return Out::failure(frame.error());
  auto result = deblur(frame.value(), model, options);
  if (result.ok()) result.value().latent = frame.value().to_camera(result.value().latent);
  return result;
}

}  // namespace flutterscan::imaging
