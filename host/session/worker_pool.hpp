#pragma once
// The worker pool (docs/session.md, "The pipeline"): `processing.workers`
// threads take FrameJobs from the bounded queue, process each
// (frame_processing.hpp) and send every outcome to the results thread, in
// whatever order they finish.

#include <thread>
#include <vector>

#include "capture/camera_source.hpp"
#include "imaging/capture_model.hpp"
#include "imaging/flat_field.hpp"
#include "session/frame_processing.hpp"
#include "session/pipeline.hpp"
#include "session/session_config.hpp"

namespace flutterscan::session {

/// \brief Measures FFT plans for the rows along the motion of frames of
/// `format` (blurs up to 256 px), before the session streams: a worker that
/// planned on its first frame would stall the queue.
void plan_row_ffts(const capture::FrameFormat& format, imaging::Direction direction);

class WorkerPool {
 public:
  /// \brief Starts the workers on `pipeline`'s jobs; `config` and `flat` (may
  /// be null) must outlive join(). `frame_rate_hz` (> 0): the camera's, the
  /// frames' share of the workers until their timestamps show it (a busy
  /// frame's decode is bounded from the first frame on). `live`: frames arrive
  /// as they are exposed (capture::CameraSource::live()), so each has a deadline.
  WorkerPool(Pipeline& pipeline, const SessionConfig& config, const imaging::FlatField* flat,
             double frame_rate_hz = 0, bool live = false);
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;
  ~WorkerPool() { join(); }

  /// \brief Waits for the workers: they end once the job queue is closed and empty.
  void join();

 private:
  WorkerShared shared_;  ///< the last blur estimate, the second passes' budget
  std::vector<std::thread> threads_;
};

}  // namespace flutterscan::session
