#include "session/worker_pool.hpp"

#include <utility>

#include "imaging/motion_frame.hpp"
#include "imaging/row_fft.hpp"

namespace flutterscan::session {
namespace {

/// Blurs up to this long deblur with FFT plans measured before the session
/// streams (longer ones with estimated plans, about 20% slower).
constexpr int kLongestPlannedBlurPx = 256;

}  // namespace

void plan_row_ffts(const capture::FrameFormat& format, imaging::Direction direction) {
  imaging::measure_row_ffts(imaging::length_along_motion(direction, format.width, format.height),
                            kLongestPlannedBlurPx + 2);
}

WorkerPool::WorkerPool(Pipeline& pipeline, const SessionConfig& config,
                       const imaging::FlatField* flat, double frame_rate_hz, bool live)
    : shared_(config) {
  if (frame_rate_hz > 0) shared_.second_pass.expect_period_ms(1000 / frame_rate_hz);
  shared_.live_arrivals = live;
  for (int w = 0; w < config.processing.workers; ++w)
    threads_.emplace_back([this, &pipeline, &config, flat] {
      FrameJob job;
      while (pipeline.jobs.pop(job)) {
        job.waiting_behind = pipeline.jobs.size();
        FrameOutcome o = process_frame(job, config, shared_, flat);
        if (!o.processed) ++pipeline.processing_errors;
        pipeline.outcomes.push(std::move(o));
      }
    });
}

void WorkerPool::join() {
  for (auto& t : threads_)
    if (t.joinable()) t.join();
}

}  // namespace flutterscan::session
