#pragma once
// A worker's work on one frame (docs/session.md, "Descriptor" to "Decode"):
// the frame's model from its exposure event, the frame in electrons
// (flat-field corrected), the simplest model that fits and its deblur
// (model_fit.hpp; raw Bayer frames: the grey model on their raw planes), the
// paper found along the motion, the codes read (processing.decode_area), the
// cascade's second pass on the label windows that read nothing
// (second_pass.hpp), and the labels judged: each whole label in view is a
// sighting, read or not.

#include <atomic>

#include "imaging/deblur.hpp"
#include "imaging/flat_field.hpp"
#include "reader/region_tiles.hpp"
#include "session/pipeline.hpp"
#include "session/second_pass.hpp"
#include "session/session_config.hpp"

namespace flutterscan::session {

/// \brief What the workers share from frame to frame.
struct WorkerShared {
  explicit WorkerShared(const SessionConfig& config)
      : last_blur_px(config.optics.nominal_blur_px),
        second_pass(config.processing.second_pass_ms, config.processing.workers),
        decode_ms_per_mpx(config.processing.decode_area == reader::DecodeArea::kLabels
                              ? reader::view_cost_ms_per_mpx(config.processing.symbologies,
                                                             config.processing.try_rotate)
                              : 0) {}
  /// The last confident blur estimate: read when a frame without an encoder has
  /// no edges along the motion, updated by each new estimate.
  std::atomic<double> last_blur_px;
  /// The latest refined frame's refined / encoder blur (0: none yet): a frame
  /// taken while the workers are behind (behind_queue()) uses it unrefined
  /// (before any, 1: the encoder's blur, as a frame without edges keeps).
  std::atomic<double> motion_ratio{0};
  /// The cascade's CPU budget for second passes.
  SecondPassBudget second_pass;
  /// Where codes were read lately on the belt: no second pass for an object read already.
  BeltReads belt_reads;
  /// Where the first pass decoded windows lately on the belt: within a frame's
  /// decode budget, the regions not tried yet go first.
  BeltReads belt_tried;
  /// What a window's first view has cost a megapixel lately, ms (from
  /// reader::view_cost_ms_per_mpx() until frames say; 0 for decode area
  /// "frame"): the first pass's decode cuts regions to its budget by it.
  std::atomic<double> decode_ms_per_mpx;
  /// Frames arrive as they are exposed (capture::CameraSource::live()): their
  /// arrival is the line's, and processing.latency_ms "auto" sets each a
  /// deadline. Set before the workers start.
  bool live_arrivals = false;
};

/// \brief Whether a frame that left `waiting` frames in a queue of
/// `queue_depth` finds the workers behind: half the queue or more (at least
/// one frame) waits. Such a frame skips the motion refinement (about a quarter
/// of a frame's first pass at 300 e-) so that the queue drains instead of
/// overflowing.
bool behind_queue(std::size_t waiting, std::size_t queue_depth);

/// \brief The first pass's deblur options under `processing`: its method and
/// threads, FFT plans measured before streaming (plan_row_ffts), flat rows skipped.
imaging::DeblurOptions deblur_options(const ProcessingConfig& processing);

/// \brief Processes `job` (its frame moved into the outcome) under `config`,
/// corrected by `flat` when not null, with what the workers share. A frame
/// that cannot be processed comes back with processed = false and its error
/// logged.
FrameOutcome process_frame(FrameJob& job, const SessionConfig& config, WorkerShared& shared,
                           const imaging::FlatField* flat);

}  // namespace flutterscan::session
