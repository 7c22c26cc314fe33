#pragma once
// The capture stage (docs/session.md, "Drops"): the session's own thread reads
// the camera, hands frames and the controller's exposure events to the
// matching stage and sends the decided frames on. It never blocks on the
// workers: a frame that finds their queue full is dropped here (flag
// dropped), the only place the session drops frames. It ends at the camera's
// end, a camera error, a stop request or a limit (max_frames, max_seconds);
// then it waits for the controller's events still in flight and decides every
// frame left waiting.

#include <nlohmann/json.hpp>

#include <atomic>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <string>

#include "capture/camera_source.hpp"
#include "device/controller_client.hpp"
#include "session/matching_stage.hpp"
#include "session/pipeline.hpp"
#include "session/session_config.hpp"

namespace flutterscan::session {

/// \brief Exposure events on their way from the controller client's reader
/// thread to the capture thread.
class EventInbox {
 public:
  /// \brief An event notice from the controller (reader thread).
  void receive(const device::EventNotice& notice);
  /// \brief The events received since the last call (capture thread).
  std::deque<ExposureRecord> take();
  /// \brief Events received so far.
  std::uint64_t received() const { return received_; }
  /// \brief Events the controller's frame counter says were lost before reaching the host.
  std::uint64_t missing() const { return missing_; }

 private:
  std::mutex mutex_;
  std::deque<ExposureRecord> events_;
  std::atomic<std::uint64_t> received_{0};
  std::atomic<std::uint64_t> missing_{0};
};

/// \brief Why capture ended.
struct CaptureEnd {
  std::string stopped_by = "end of frames";  ///< as summary.json's stopped_by
  std::string error;                         ///< the camera's error, if it ended on one
};

/// \brief Runs capture on `camera` (started) until it ends: frames matched by
/// `matching`, jobs sent to `pipeline.jobs` or dropped, other outcomes to
/// `pipeline.outcomes`, lines for events without frame to `log`. Stops the
/// camera; leaves the queues open.
CaptureEnd run_capture(capture::CameraSource& camera, EventInbox& inbox, MatchingStage& matching,
                       Pipeline& pipeline, const ProcessingConfig& limits, std::int64_t start_ns,
                       const std::atomic<bool>& stop,
                       const std::function<void(const nlohmann::json&)>& log);

}  // namespace flutterscan::session
