#pragma once
// The light level E (docs/conventions.md, "Light level E and the cap c": the electrons per channel
// a white object collects in one exposure with every LED on continuously), measured from frames of
// the belt lit by a known probe pattern.
//
// The capture model is linear in E: under the probe, a white object gives
// channel c the electrons sum_k M[c][k] n_k I_k, with I_k = min(E / n_k,
// cap E / L) the light budget, so E = (measured paper electrons) / (paper
// reflectance x the same sum at E = 1). The paper is the brightest extended
// surface in the frames: each frame's grey (the channels' electrons summed,
// black level removed) is smoothed by a small box; starting from a high
// quantile of those values, a mean shift with a window of a few noise
// standard deviations (at least +-4%) settles on the brightest plateau, and
// its pixels are the paper. Assumption: that plateau is label paper of the
// given reflectance (1 unless told); a frame with no label in view would
// take the belt for paper and read E too low (`background_electrons` helps
// to notice).

#include <cstddef>
#include <string>
#include <vector>

#include "flutterscan/common/result.hpp"
#include "imaging/capture_model.hpp"
#include "imaging/image.hpp"

namespace flutterscan::imaging {

struct LightLevelOptions {
  double paper_reflectance = 1.0;  ///< reflectance of the brightest paper (white = 1)
  int smooth_radius_px = 3;        ///< box of (2r + 1)^2 pixels over the grey before the search
  double start_quantile = 0.998;   ///< where the search for the brightest plateau starts
  std::size_t min_pixels = 400;    ///< paper pixels needed (over all frames)
  double max_saturated = 0.01;     ///< share of paper pixels allowed at the ceiling
  double min_snr = 5;              ///< paper grey over its smoothed noise, at least
};

struct LightLevel {
  double electrons = 0;             ///< E, e- per channel under rect-white
  double paper_electrons = 0;       ///< mean e- of the paper pixels, summed over channels
  double white_per_unit_e = 0;      ///< what white gives under the probe, summed, at E = 1
  double background_electrons = 0;  ///< median of the smoothed grey over all frames
  std::size_t pixels = 0;           ///< paper pixels the level comes from
  int frames = 0;                   ///< frames searched
  double saturated_share = 0;       ///< of the paper pixels, with a channel at the ceiling
};

/// \brief The capture model of `probe` at light level E = 1 (I_k from the light
/// budget with `cap`), with the rest of `camera` (crosstalk, gain, black level,
/// bit depth, channels): what estimate_light_level divides by.
CaptureModel unit_light_model(const CaptureModel& camera, const LedCode& probe, double cap);

/// \brief E from frames in DN (one plane per channel, all of one size) lit by
/// the probe of `unit_model` (unit_light_model). Fails, naming why, with no
/// frames, frames of mixed sizes, a paper plateau of fewer than min_pixels,
/// one that saturates, or one lost in noise.
Result<LightLevel, std::string> estimate_light_level(const std::vector<Image>& dn_frames,
                                                     const CaptureModel& unit_model,
                                                     const LightLevelOptions& options = {});

}  // namespace flutterscan::imaging
