#pragma once
// A worker's work on one frame (docs/session.md, "Descriptor" to "Decode"):
// the frame's model from its exposure event, the frame in electrons
// (flat-field corrected), the simplest model that fits and its deblur
// (model_fit.hpp; raw Bayer frames: the grey model on their raw planes), the
// paper found along the motion, the codes read (processing.decode_area), and
// the labels judged: each whole label in view is a sighting, read or not.

#include <atomic>

#include "imaging/flat_field.hpp"
#include "session/pipeline.hpp"
#include "session/session_config.hpp"

namespace flutterscan::session {

/// \brief Processes `job` (its frame moved into the outcome) under `config`,
/// corrected by `flat` when not null. `last_blur_px` is the last confident
/// blur estimate, shared by the workers: read when a frame without an encoder
/// has no edges along the motion, updated by each new estimate. A frame that
/// cannot be processed comes back with processed = false and its error logged.
FrameOutcome process_frame(FrameJob& job, const SessionConfig& config,
                           std::atomic<double>& last_blur_px, const imaging::FlatField* flat);

}  // namespace flutterscan::session
