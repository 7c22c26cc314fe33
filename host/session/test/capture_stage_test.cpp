// The capture stage: frames from the camera matched and sent on; a full queue
// to the workers drops frames there and counts every drop; a stop request, a
// frame limit and a camera error end capture, each said so.
#include "session/capture_stage.hpp"

#include <gtest/gtest.h>

#include <deque>

#include "session/test/stage_test_support.hpp"

namespace flutterscan::session {
namespace {

using testing::exposure;
using testing::frame_of;

/// A camera that delivers `frames` frames of exposures 0, 1, ... then ends (or fails).
class ScriptedCamera : public capture::CameraSource {
 public:
  ScriptedCamera(int frames, bool fail_at_end) : frames_(frames), fail_at_end_(fail_at_end) {}
  std::string name() const override { return "scripted"; }
  std::string open() override { return ""; }
  std::string configure(const capture::CameraSettings&) override { return ""; }
  capture::CameraSettings settings() const override { return {}; }
  capture::FrameFormat format() const override { return frame_of(0).format; }
  std::string start() override { return ""; }
  capture::FrameWait next_frame(capture::Frame& frame, std::chrono::milliseconds,
                                std::string& error) override {
    if (delivered_ == frames_) {
      if (!fail_at_end_) return capture::FrameWait::kEnd;
      error = "scripted: the cable came out";
      return capture::FrameWait::kError;
    }
    frame = frame_of(delivered_++, 0);
    return capture::FrameWait::kFrame;
  }
  void stop() override { stopped = true; }
  capture::CameraCounters counters() const override { return {}; }

  bool stopped = false;

 private:
  int frames_;
  bool fail_at_end_;
  int delivered_ = 0;
};

void receive_events(EventInbox& inbox, int count) {
  for (int k = 0; k < count; ++k) {
    device::EventNotice notice;
    const ExposureRecord e = exposure(k);
    notice.event.frame_counter = e.frame_counter;
    notice.event.start_time_us = e.start_us;
    notice.event.encoder_delta = e.encoder_delta;
    notice.event.slot_time_us = e.slot_time_us;
    notice.event.slot_count = e.slot_count;
    inbox.receive(notice);
  }
}

struct CaptureRun {
  CaptureEnd end;
  std::vector<FrameJob> jobs;
  std::vector<FrameOutcome> outcomes;
  std::vector<nlohmann::json> log;
  std::uint64_t captured = 0, dropped = 0;
};

/// Capture of `frames` frames with all their events, the workers' queue `queue_depth` deep
/// and nobody taking from it.
CaptureRun capture(ScriptedCamera& camera, int frames, std::size_t queue_depth,
                   const ProcessingConfig& limits, bool stop_requested) {
  EventInbox inbox;
  receive_events(inbox, frames);
  OpticsConfig optics;
  MatchingStage matching(2000, optics);
  Pipeline pipeline(queue_depth);
  const std::atomic<bool> stop{stop_requested};
  CaptureRun run;
  run.end = run_capture(camera, inbox, matching, pipeline, limits, 0, stop,
                        [&](const nlohmann::json& line) { run.log.push_back(line); });
  pipeline.jobs.close();
  pipeline.outcomes.close();
  FrameJob job;
  while (pipeline.jobs.pop(job)) run.jobs.push_back(std::move(job));
  FrameOutcome outcome;
  while (pipeline.outcomes.pop(outcome)) run.outcomes.push_back(std::move(outcome));
  run.captured = pipeline.frames_captured;
  run.dropped = pipeline.frames_dropped;
  return run;
}

TEST(CaptureStage, AFullQueueDropsFramesThereAndCountsEachDrop) {
  ScriptedCamera camera(6, false);
  const CaptureRun run = capture(camera, 6, 2, {}, false);
  EXPECT_EQ(run.end.stopped_by, "end of frames");
  EXPECT_TRUE(run.end.error.empty());
  EXPECT_TRUE(camera.stopped);
  EXPECT_EQ(run.captured, 6u);
  ASSERT_EQ(run.jobs.size(), 2u);
  EXPECT_EQ(run.jobs[0].index, 0u);
  EXPECT_EQ(run.jobs[1].index, 1u);
  EXPECT_EQ(run.dropped, 4u);
  ASSERT_EQ(run.outcomes.size(), 4u);
  for (const auto& o : run.outcomes) {
    EXPECT_FALSE(o.processed);
    EXPECT_EQ(o.log["flags"], nlohmann::json::array({"dropped"}));
    EXPECT_EQ(o.log["event"]["counter"], o.sequence + 1);
  }
  EXPECT_TRUE(run.log.empty());
}

TEST(CaptureStage, AStopRequestEndsCaptureBeforeTheNextFrame) {
  ScriptedCamera camera(6, false);
  const CaptureRun run = capture(camera, 6, 8, {}, true);
  EXPECT_EQ(run.end.stopped_by, "stop request (SIGINT)");
  EXPECT_EQ(run.captured, 0u);
  EXPECT_TRUE(run.jobs.empty());
  EXPECT_TRUE(camera.stopped);
  // The events no frame claimed are logged once capture is over.
  EXPECT_EQ(run.log.size(), 6u);
}

TEST(CaptureStage, MaxFramesEndsCaptureAtTheLimit) {
  ScriptedCamera camera(6, false);
  ProcessingConfig limits;
  limits.max_frames = 3;
  const CaptureRun run = capture(camera, 6, 8, limits, false);
  EXPECT_EQ(run.end.stopped_by, "max_frames");
  EXPECT_EQ(run.captured, 3u);
  EXPECT_EQ(run.jobs.size(), 3u);
}

TEST(CaptureStage, ACameraErrorEndsCaptureNamingIt) {
  ScriptedCamera camera(2, true);
  const CaptureRun run = capture(camera, 2, 8, {}, false);
  EXPECT_EQ(run.end.stopped_by, "camera error");
  EXPECT_EQ(run.end.error, "scripted: the cable came out");
  EXPECT_EQ(run.jobs.size(), 2u);
}

TEST(EventInbox, CountsEventsAndTheOnesMissingBeforeThem) {
  EventInbox inbox;
  receive_events(inbox, 3);
  device::EventNotice late;
  late.event.frame_counter = 7;
  late.frames_missing_before = 3;
  inbox.receive(late);
  EXPECT_EQ(inbox.received(), 4u);
  EXPECT_EQ(inbox.missing(), 3u);
  const auto events = inbox.take();
  ASSERT_EQ(events.size(), 4u);
  EXPECT_EQ(events.back().frame_counter, 7u);
  EXPECT_TRUE(inbox.take().empty());
}

}  // namespace
}  // namespace flutterscan::session
