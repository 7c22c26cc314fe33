#include "imaging/row_phase_deblur.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

#include "imaging/exposure_timeline.hpp"
#include "imaging/image_checks.hpp"
#include "imaging/limits.hpp"

namespace flutterscan::imaging {

Result<Plane, std::string> deblur_row_phases(const MotionFrame& frame, const CaptureModel& model,
                                             std::span<const double> row_phase_slots,
                                             const DeblurOptions& options, double phase_step) {
  using Out = Result<Plane, std::string>;
  if (auto problem = capture_model_problem(model); !problem.empty()) return Out::failure(problem);
  if (auto problem = model_scale_problem(model); !problem.empty()) return Out::failure(problem);
  if (model.bayer_rggb) return Out::failure("the per-row phase model takes RGB or mono frames");
  if (!moves_along_x(frame.direction()))
    return Out::failure("the per-row phase model needs motion along x (rows of the readout)");
  if (frame.channel_count() != model.channels)
    return Out::failure("the frame has " + std::to_string(frame.channel_count()) +
                        " channels but the capture model " + std::to_string(model.channels));
  if (static_cast<int>(row_phase_slots.size()) != frame.lines())
    return Out::failure(
        "one code phase per row is needed: " + std::to_string(row_phase_slots.size()) +
        " phases for " + std::to_string(frame.lines()) + " rows");
  for (double p : row_phase_slots)
    if (!std::isfinite(p)) return Out::failure("row code phases must be finite");
  if (!(phase_step >= kMinRowPhaseStep && phase_step <= 1))
    return Out::failure("the phase step must be in [" + std::to_string(kMinRowPhaseStep) +
                        ", 1] slots");
  if (auto problem = blur_fit_problem(model.blur_px, frame.along(), 0, "the blur");
      !problem.empty())
    return Out::failure(problem);
  // As deblur: a model whose every channel gets less than kMinLitElectrons (a crosstalk of
  // 1e-47 from the one lit LED) deconvolves 0 / 0 (a fuzz finding, pipeline/corpus/
  // finding-not-finite-6).
  double brightest = 0;
  for (int c = 0; c < model.channels; ++c) {
    double gain = 0;
    for (double tap : channel_psf(model, c)) gain += tap;
    brightest = std::max(brightest, gain);
  }
  if (!(brightest >= kMinLitElectrons))
    return Out::failure("the capture model lights no channel: every PSF is zero (or below " +
                        std::to_string(kMinLitElectrons) + " e-)");
  if (!(options.gradient_variance > 0) || !std::isfinite(options.gradient_variance))
    return Out::failure("the prior gradient variance must be a finite number > 0");

  const std::vector<Plane>& rows = frame.image().channels;
  std::vector<double> variance;
  for (const auto& plane : rows)
    variance.push_back(channel_noise_variance(model, noise_level_mean(plane)));
  const int width = frame.along();
  // Rows per quantised phase (in units of phase_step, modulo the code's cycle).
  // The phase is reduced to one cycle first (fmod is exact): a finite phase of any size
  // then quantises to at most L / kMinRowPhaseStep steps, well inside long long.
  const double cycle = model.code.length();
  const auto steps = std::llround(cycle / phase_step);
  std::map<long long, std::vector<int>> groups;
  for (int y = 0; y < frame.lines(); ++y) {
    double phase = std::fmod(row_phase_slots[static_cast<std::size_t>(y)], cycle);
    if (phase < 0) phase += cycle;
    long long q = std::llround(phase / phase_step) % steps;
    if (q < 0) q += steps;
    groups[q].push_back(y);
  }
  Plane latent(width, frame.lines());
  for (const auto& [q, members] : groups) {
    const auto segments = cyclic_phase_segments(model, static_cast<double>(q) * phase_step);
    std::vector<ChannelPsf> psfs;
    for (int c = 0; c < model.channels; ++c)
      psfs.push_back(
          {timeline_channel_psf(model, c, segments), variance[static_cast<std::size_t>(c)]});
    std::vector<Plane> group_rows;
    for (const auto& plane : rows) {
      Plane stacked(width, static_cast<int>(members.size()));
      for (std::size_t i = 0; i < members.size(); ++i) {
        const auto source = plane.row(members[i]);
        std::copy(source.begin(), source.end(), stacked.row(static_cast<int>(i)).begin());
      }
      group_rows.push_back(std::move(stacked));
    }
    const Plane solved = deconvolve_motion_rows(psfs, group_rows, 1.0 / options.gradient_variance,
                                                model.read_noise * model.read_noise, options);
    for (std::size_t i = 0; i < members.size(); ++i) {
      const auto source = solved.row(static_cast<int>(i));
      std::copy(source.begin(), source.end(), latent.row(members[i]).begin());
    }
  }
  undo_psf_lead(latent, pixel_model_lead(model.pixel_model));
  return Out::success(std::move(latent));
}

}  // namespace flutterscan::imaging
