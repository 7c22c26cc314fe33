#include "session/model_fit.hpp"

#include <chrono>
#include <cmath>

#include "imaging/blur_estimate.hpp"
#include "imaging/model_choice.hpp"
#include "imaging/model_guards.hpp"
#include "imaging/per_channel_wiener.hpp"
#include "imaging/row_phase_deblur.hpp"
#include "session/read_record.hpp"

namespace flutterscan::session {
namespace {

/// Milliseconds since `since`, to 0.01 ms; `since` moves to now.
double lap_ms(std::chrono::steady_clock::time_point& since) {
  const auto now = std::chrono::steady_clock::now();
  const double ms = std::chrono::duration<double, std::milli>(now - since).count();
  since = now;
  return rounded(ms, 2);
}

/// Refines the encoder's motion on the frame (ModelFitConfig::blur_tolerance):
/// `model` takes the refined motion when the frame has edges along it and the
/// result is neither on the tolerance's edge nor unfit (then flagged).
void refine_encoder_motion(const imaging::MotionFrame& frame, imaging::CaptureModel& model,
                           double tolerance, FittedFrame& out) {
  imaging::MotionRefinementOptions options;
  options.tolerance = tolerance;
  const auto r = imaging::refine_motion(frame, model, options);
  if (!r.ok()) {
    out.log["motion"] = {{"error", r.error()}};
    return;
  }
  const auto& m = r.value();
  nlohmann::json log = {{"encoder_blur_px", rounded(model.blur_px, 2)},
                        {"edges", m.edges},
                        {"residual", rounded(m.residual_per_sample, 2)}};
  if (m.edges) {
    log["refined_blur_px"] = rounded(m.blur_px, 3);
    log["standard_error_px"] = rounded(m.standard_error_px, 3);
    if (m.accelerating) log["speed_ratio"] = rounded(m.speed_ratio, 3);
    if (m.wandering) {
      nlohmann::json offsets = nlohmann::json::array();
      for (double v : m.block_offsets_px) offsets.push_back(rounded(v, 2));
      log["block_offsets_px"] = std::move(offsets);
    }
  }
  out.refinement = m;
  if (m.edges && m.outside_tolerance) {
    out.flags.emplace_back("blur-off-encoder");
    log["used"] = false;
  } else if (m.edges && m.residual_per_sample > imaging::kUnfitMotionResidual) {
    out.flags.emplace_back("motion-unfit");
    log["used"] = false;
  } else if (m.edges) {
    model = imaging::with_refined_motion(std::move(model), m);
    out.refinement_used = true;
    log["used"] = true;
  } else {
    log["used"] = false;
  }
  out.log["motion"] = std::move(log);
}

/// The blur searched around a nominal one: -20% to +25%, inside the frame.
std::pair<double, double> blur_range(double nominal, int along) {
  return {std::max(2.0, 0.8 * nominal), std::min(1.25 * nominal, along / 2.0)};
}

}  // namespace

Result<FittedFrame, std::string> deblur_fitting_model(double saturated_share,
                                                      const imaging::MotionFrame& frame,
                                                      imaging::CaptureModel model,
                                                      const imaging::DeblurOptions& options,
                                                      const ModelFitConfig& config,
                                                      std::uint64_t frame_index) {
  using Out = Result<FittedFrame, std::string>;
  FittedFrame out;
  imaging::GuardReport guards;
  auto lap = std::chrono::steady_clock::now();
  nlohmann::json& times = out.log["fit_ms"];

  // 1. The blur.
  const bool check_blur = config.encoder && config.blur_check_every > 0 &&
                          frame_index % static_cast<std::uint64_t>(config.blur_check_every) == 0;
  if ((!config.encoder || check_blur) && frame.channel_count() >= 2) {
    const auto [lo, hi] = blur_range(model.blur_px, frame.along());
    const auto estimate =
        imaging::estimate_blur(frame, model, lo, hi, std::max(1, frame.lines() / 90));
    if (estimate.ok()) {
      out.log["blur_estimate_px"] = rounded(estimate.value().blur_px, 2);
      if (std::isfinite(estimate.value().standard_error_px))
        out.log["blur_estimate_se_px"] = rounded(estimate.value().standard_error_px, 3);
      if (!config.encoder) {
        if (std::isfinite(estimate.value().standard_error_px)) {
          model.blur_px = estimate.value().blur_px;
          out.estimated_blur_px = model.blur_px;
        } else {
          if (config.fallback_blur_px > 0) model.blur_px = config.fallback_blur_px;
          out.flags.emplace_back("blur-unknown");  // no edges along the motion
        }
      } else {
        guards.blur_checked = true;
        guards.blur_disagrees = imaging::blur_disagrees(model.blur_px, estimate.value());
      }
    } else {
      out.log["blur_estimate_error"] = estimate.error();
    }
  }

  times["blur_estimate"] = lap_ms(lap);

  // The encoder's motion refined on the frame (after the check, which judges the encoder).
  if (config.encoder && config.blur_tolerance > 0 && frame.channel_count() >= 2 &&
      model.code.leds() >= 2) {
    if (config.reuse_motion_ratio > 0) {
      out.log["motion"] = {{"encoder_blur_px", rounded(model.blur_px, 2)},
                           {"reused_ratio", rounded(config.reuse_motion_ratio, 5)},
                           {"used", false}};
      model.blur_px *= config.reuse_motion_ratio;
      out.flags.emplace_back("motion-reused");
    } else {
      refine_encoder_motion(frame, model, config.blur_tolerance, out);
    }
  }
  times["refine_motion"] = lap_ms(lap);

  // 2. The model, and the deblur under it.
  const auto choice =
      config.choose_latent
          ? imaging::choose_frame_model(frame, model, config.line_time_us > 0, config.encoder)
          : imaging::FrameModelChoice{imaging::LatentModel::kGrey, config.line_time_us > 0,
                                      config.encoder, 0};
  times["model_choice"] = lap_ms(lap);
  out.log["model"] = {{"chosen", choice.describe()},
                      {"grey_residual", rounded(choice.grey_residual, 2)},
                      {"blur_px", rounded(model.blur_px, 2)}};
  if (model.speed_ratio != 1) out.log["model"]["speed_ratio"] = rounded(model.speed_ratio, 3);
  if (choice.latent == imaging::LatentModel::kPerChannel && frame.channel_count() == 3) {
    auto result = imaging::deblur_per_channel(frame, model, 1.0 / options.gradient_variance,
                                              {.threads = options.threads,
                                               .output = imaging::PerChannelOutput::kGreyOnly,
                                               .plan_effort = options.plan_effort});
    if (!result.ok()) return Out::failure(result.error());
    out.latent = std::move(result.value().grey);
    out.per_channel = true;
  } else if (choice.per_row_phase) {
    std::vector<double> phases(static_cast<std::size_t>(frame.lines()));
    const double slots = model.code.length();
    for (std::size_t r = 0; r < phases.size(); ++r)
      phases[r] =
          std::fmod(static_cast<double>(r) * config.line_time_us / config.slot_time_us, slots);
    auto result = imaging::deblur_row_phases(frame, model, phases, options);
    if (!result.ok()) return Out::failure(result.error());
    out.latent = std::move(result.value());
  } else {
    auto result = imaging::deblur(frame, model, options);
    if (!result.ok()) return Out::failure(result.error());
    out.latent = std::move(result.value().latent);
    out.grey_global = true;
    if (options.skip_flat_rows) out.log["model"]["flat_rows"] = result.value().flat_rows;
    times["deblur"] = lap_ms(lap);
    // The residual check needs the grey global model the frame was deblurred with.
    guards.residual_ratio =
        imaging::residual_ratio(frame, out.latent, model, std::max(4, frame.lines() / 32));
  }

  if (!times.contains("deblur")) times["deblur"] = lap_ms(lap);

  // 3. Guards.
  guards.saturated_share = saturated_share;
  out.log["guards"] = {{"saturated_share", rounded(guards.saturated_share, 5)},
                       {"residual_ratio", rounded(guards.residual_ratio, 2)}};
  if (guards.blur_checked) out.log["guards"]["blur_disagrees"] = guards.blur_disagrees;
  for (auto& flag : guards.flags()) out.flags.push_back(flag);
  times["guards"] = lap_ms(lap);  // with the residual check after a global deblur
  out.model = std::move(model);
  return Out::success(std::move(out));
}

}  // namespace flutterscan::session
