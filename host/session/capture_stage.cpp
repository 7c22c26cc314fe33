#include "session/capture_stage.hpp"

#include <chrono>
#include <thread>
#include <utility>
#include <variant>

#include "session/line_devices.hpp"
#include "session/session_clock.hpp"

namespace flutterscan::session {
namespace {

/// Sends decided frames on: jobs to the workers (or dropped when their queue is
/// full), finished outcomes to the results; then the events no frame claimed.
void send_on(std::vector<MatchedFrame> decided, MatchingStage& matching, Pipeline& pipeline,
             const std::function<void(const nlohmann::json&)>& log) {
  for (auto& m : decided) {
    if (auto* outcome = std::get_if<FrameOutcome>(&m)) {
      pipeline.outcomes.push(std::move(*outcome));
      continue;
    }
    FrameJob& job = std::get<FrameJob>(m);
    const std::uint64_t index = job.index;
    const std::uint64_t sequence = job.frame.sequence;
    const std::int64_t camera_ns = job.frame.timestamp_ns;
    const std::uint32_t counter = job.event.frame_counter;
    if (!pipeline.jobs.try_push(std::move(job))) {
      // The one place frames are dropped: processing is behind.
      ++pipeline.frames_dropped;
      FrameOutcome o;
      o.index = index;
      o.sequence = sequence;
      o.log = {{"index", index},
               {"sequence", sequence},
               {"camera_ns", camera_ns},
               {"event", {{"counter", counter}}},
               {"flags", {"dropped"}},
               {"why", "processing behind: the queue to the workers was full"}};
      pipeline.outcomes.push(std::move(o));
    }
  }
  for (const auto& line : matching.take_orphan_event_logs()) log(line);
}

void take_events(EventInbox& inbox, MatchingStage& matching) {
  for (const auto& e : inbox.take()) matching.add_event(e);
}

}  // namespace

void EventInbox::receive(const device::EventNotice& notice) {
  missing_ += notice.frames_missing_before;
  ++received_;
  std::lock_guard lock(mutex_);
  events_.push_back(exposure_record(notice));
}

std::deque<ExposureRecord> EventInbox::take() {
  std::deque<ExposureRecord> got;
  std::lock_guard lock(mutex_);
  got.swap(events_);
  return got;
}

CaptureEnd run_capture(capture::CameraSource& camera, EventInbox& inbox, MatchingStage& matching,
                       Pipeline& pipeline, const ProcessingConfig& limits, std::int64_t start_ns,
                       const std::atomic<bool>& stop,
                       const std::function<void(const nlohmann::json&)>& log) {
  CaptureEnd end;
  for (;;) {
    if (stop) {
      end.stopped_by = "stop request (SIGINT)";
      break;
    }
    if (limits.max_frames != 0 && pipeline.frames_captured >= limits.max_frames) {
      end.stopped_by = "max_frames";
      break;
    }
    if (limits.max_seconds > 0 && ms_between(start_ns, now_ns()) * 1e-3 >= limits.max_seconds) {
      end.stopped_by = "max_seconds";
      break;
    }
    capture::Frame frame;
    std::string frame_error;
    const auto got = camera.next_frame(frame, std::chrono::milliseconds(200), frame_error);
    if (got == capture::FrameWait::kEnd) break;
    if (got == capture::FrameWait::kError) {
      end.error = frame_error;
      end.stopped_by = "camera error";
      break;
    }
    take_events(inbox, matching);
    if (got == capture::FrameWait::kTimeout) {
      // Late events may settle waiting frames.
      send_on(matching.decide_waiting(now_ns()), matching, pipeline, log);
      continue;
    }
    ++pipeline.frames_captured;
    if (frame.host_arrival_ns == 0) frame.host_arrival_ns = now_ns();
    send_on(matching.add_frame(std::move(frame)), matching, pipeline, log);
  }
  camera.stop();
  // Events still in flight from the controller: wait until none arrive for 100 ms (1 s at most).
  for (int i = 0; i < 10; ++i) {
    const std::uint64_t before = inbox.received();
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    if (inbox.received() == before) break;
  }
  take_events(inbox, matching);
  send_on(matching.flush(), matching, pipeline, log);
  return end;
}

}  // namespace flutterscan::session
