#pragma once
// The exposure as a timeline of segments, for PSFs beyond the nominal model of
// capture_model.hpp: a belt whose speed varies within the exposure (each slot
// covers its own stretch of pixels) and a rolling-shutter row that sees the
// cyclically repeated pattern from its own phase (fractional slots exact).
// channel_psf() is the PSF of the model's own slot_segments().

#include <cstdint>
#include <span>
#include <vector>

#include "imaging/capture_model.hpp"

namespace flutterscan::imaging {

/// \brief A stretch of the exposure during which one LED mask is lit.
struct ExposureSegment {
  double start_px = 0;       ///< object displacement at the segment's start
  double width_px = 0;       ///< displacement during the segment
  std::uint8_t mask = 0;     ///< code bits lit (the code's digit)
  double slot_fraction = 1;  ///< share of a whole slot's light (1 = a whole slot)
};

/// \brief The model's own timeline: slot t over [slot_edges[t], slot_edges[t + 1]]
/// (t s to (t + 1) s, s = blur / L, at constant speed).
std::vector<ExposureSegment> slot_segments(const CaptureModel& model);

/// \brief Slot t covers [boundaries[t], boundaries[t + 1]) pixels (L + 1
/// non-decreasing values): a speed that varies from slot to slot.
std::vector<ExposureSegment> segments_from_boundaries(const LedCode& code,
                                                      std::span<const double> boundaries);

/// \brief A row whose exposure starts `phase_slots` (any real) into the
/// cyclically repeated pattern, at uniform speed: it sees slots phase,
/// phase + 1, ... modulo L, with the partial slots at either end weighted by
/// the part of them it sees. Phase 0 gives uniform_segments().
std::vector<ExposureSegment> cyclic_phase_segments(const CaptureModel& model, double phase_slots);

/// \brief Channel c's PSF (e- per unit reflectance) for a timeline: each
/// segment's light laid over the pixels it moved across by the model's pixel
/// model, and the ambient light over every segment in proportion to its time
/// (slot_fraction / L of the exposure).
std::vector<double> timeline_channel_psf(const CaptureModel& model, int channel,
                                         std::span<const ExposureSegment> segments);

/// \brief Every channel's timeline_channel_psf() at once, each segment's shape
/// over the pixels computed once for all channels (the motion refinement builds
/// them for every candidate motion). Equal to the one-channel PSFs but for
/// rounding.
std::vector<std::vector<double>> timeline_channel_psfs(const CaptureModel& model,
                                                       std::span<const ExposureSegment> segments);

/// \brief LED `led`'s PSF without crosstalk or ambient light (e- per unit
/// reflectance of its own band in its own channel): the colour model's terms.
std::vector<double> timeline_led_psf(const CaptureModel& model, int led,
                                     std::span<const ExposureSegment> segments);

}  // namespace flutterscan::imaging
