// The summary stage: summary.json's figures are the stages' counts, object
// rates and ground truth judged as docs/session.md says; percentiles between ranks.
#include "session/session_summary.hpp"

#include <gtest/gtest.h>

namespace flutterscan::session {
namespace {

ObjectResult object(const std::string& value, int seen, int decoded) {
  ObjectResult o;
  o.value = value;
  o.frames_seen = seen;
  o.frames_decoded = decoded;
  if (!value.empty()) o.values[value] = decoded;
  return o;
}

TEST(SessionSummary, CountsWhatEachStageCounted) {
  Pipeline pipeline(4);
  pipeline.frames_captured = 10;
  pipeline.frames_processed = 7;
  pipeline.frames_dropped = 2;
  pipeline.processing_errors = 1;
  const MatchingStage matching(500, OpticsConfig{});
  const EventInbox inbox;
  capture::CameraCounters camera;
  camera.frames_dropped = 3;
  camera.making_ms = 420;
  CaptureEnd end;
  end.stopped_by = "signal";
  end.error = "camera went away";
  const SessionFolder folder;
  const ResultsServer server;
  const SessionCounts counts =
      count_session(pipeline, matching, inbox, camera, end, folder, server);
  EXPECT_EQ(counts.frames_captured, 10u);
  EXPECT_EQ(counts.frames_processed, 7u);
  EXPECT_EQ(counts.frames_dropped, 2u);
  EXPECT_EQ(counts.frames_failed, 1u);
  EXPECT_EQ(counts.frames_without_event, 0u);
  EXPECT_EQ(counts.events_received, 0u);
  EXPECT_EQ(counts.camera_frames_lost, 3u);
  EXPECT_EQ(counts.camera_making_ms, 420);
  EXPECT_EQ(counts.stopped_by, "signal");
  EXPECT_EQ(counts.capture_error, "camera went away");
  EXPECT_EQ(counts.lines_sent, 0u);
  EXPECT_EQ(counts.tcp_port, server.port());
}

TEST(SessionSummary, ReportsTheStagesCountsAndJudgesTheGroundTruth) {
  SessionConfig config;
  ASSERT_EQ(check_config(config), "");
  SessionCounts counts;
  counts.camera = "sim";
  counts.controller = "virtual controller";
  counts.format.width = 640;
  counts.format.height = 240;
  counts.format.pixel_format = capture::PixelFormat::kRgb8;
  counts.frames_captured = 10;
  counts.frames_processed = 8;
  counts.frames_dropped = 1;
  counts.frames_without_event = 1;
  counts.events_received = 9;
  counts.duration_s = 2;
  counts.stopped_by = "max_frames";
  counts.capture_error = "camera gone";
  SessionResults results;
  for (auto o : {object("A", 4, 4), object("", 2, 0), object("Z", 2, 1)})
    results.objects.add(o, true);
  for (double ms : {10, 20, 30}) results.latency_ms.add(ms);
  results.stage_ms = 8 * 25;  // 8 frames processed, 25 ms of stages each
  counts.camera_making_ms = 10 * 300;
  results.truth_seen = {"A", "B"};
  results.truth_in_view = {"A", "B", "C"};
  results.models_chosen["global"] = 8;
  const nlohmann::json s = session_summary(config, counts, results);
  EXPECT_EQ(s["format"], "flutterscan-session-summary");
  EXPECT_EQ(s["frame_size"], "640x240 rgb8");
  EXPECT_EQ(s["frames_captured"], 10);
  EXPECT_EQ(s["frames_dropped"], 1);
  EXPECT_EQ(s["frames_without_event"], 1);
  EXPECT_EQ(s["fps"], 4.0);
  // The pipeline's capacity: 2 workers (the default) at 25 ms a frame; the camera's cost
  // per frame captured.
  EXPECT_EQ(config.processing.workers, 2);
  EXPECT_EQ(s["frame_stage_ms_mean"], 25.0);
  EXPECT_EQ(s["capacity_fps"], 80.0);
  EXPECT_EQ(s["camera_making_ms_mean"], 300.0);
  EXPECT_EQ(s["objects"], 3);
  EXPECT_EQ(s["objects_read"], 2);
  EXPECT_DOUBLE_EQ(s["object_read_rate"].get<double>(), 2.0 / 3.0);
  EXPECT_DOUBLE_EQ(s["mean_decode_rate_per_object"].get<double>(), (1.0 + 0.0 + 0.5) / 3.0);
  EXPECT_EQ(s["latency_ms_p50"], 20.0);
  EXPECT_EQ(s["stopped_by"], "max_frames");
  EXPECT_EQ(s["error"], "camera gone");
  EXPECT_EQ(s["models_chosen"]["global"], 8);
  EXPECT_EQ(s["ground_truth"]["labels_fully_in_view"], 2);
  EXPECT_EQ(s["ground_truth"]["labels_read"], 1);
  EXPECT_EQ(s["ground_truth"]["missed"], nlohmann::json::array({"B"}));
  EXPECT_EQ(s["ground_truth"]["wrong_values"], nlohmann::json::array({"Z"}));
  EXPECT_EQ(s["object_results"].size(), 3u);
  EXPECT_EQ(s["object_results_omitted"], 0);
  EXPECT_FALSE(s.contains("save_error"));
}

// A camera the host only receives frames from has no making cost to report, and
// with nothing processed there is no capacity to measure.
TEST(SessionSummary, NoCameraCostForARealCameraAndNoCapacityWithoutFrames) {
  SessionConfig config;
  SessionCounts counts;
  counts.frames_captured = 5;
  const SessionResults results;
  const nlohmann::json s = session_summary(config, counts, results);
  EXPECT_FALSE(s.contains("camera_making_ms_mean"));
  EXPECT_EQ(s["capacity_fps"], 0.0);
  EXPECT_EQ(s["frame_stage_ms_mean"], 0.0);
}

TEST(SessionSummary, TheReportCountsWholeSecondsOnly) {
  SessionResults results;
  for (double t : {0.1, 0.5, 1.2, 2.9, 3.1}) results.processed.add(t);
  results.objects.add(object("A", 1, 1), false);
  const ReportInputs inputs = report_inputs({{"objects", 1}}, results, LedCode{});
  // Seconds 0, 1 and 2: 2, 1 and 1 frames (second 3 is partial).
  EXPECT_EQ(inputs.frames_per_second.count(), 3u);
  EXPECT_EQ(inputs.frames_per_second.min(), 1);
  EXPECT_EQ(inputs.frames_per_second.max(), 2);
  EXPECT_EQ(inputs.frames_per_second.percentile(50), 1);
  EXPECT_EQ(inputs.objects.size(), 1u);
  EXPECT_EQ(inputs.summary["objects"], 1);
}

TEST(SessionSummary, ListsTheLatestObjectsAndCountsEveryOne) {
  SessionConfig config;
  SessionResults results;
  const std::size_t n = kObjectsListed + 37;
  for (std::size_t i = 0; i < n; ++i) {
    const bool read = i % 4 != 0;
    ObjectResult o = object(read ? std::to_string(i) : "", 3, read ? 3 : 0);
    o.id = i + 1;
    results.objects.add(o, false);
  }
  const nlohmann::json s = session_summary(config, SessionCounts{}, results);
  EXPECT_EQ(s["objects"], n);
  EXPECT_EQ(s["objects_read"], n - (n + 3) / 4);
  EXPECT_DOUBLE_EQ(s["mean_decode_rate_per_object"].get<double>(),
                   static_cast<double>(n - (n + 3) / 4) / static_cast<double>(n));
  ASSERT_EQ(s["object_results"].size(), kObjectsListed);
  EXPECT_EQ(s["object_results_omitted"], 37);
  EXPECT_EQ(s["object_results"][0]["object"], 38);  // the first 37 are in session.jsonl only
  EXPECT_EQ(s["object_results"].back()["object"], n);
  EXPECT_TRUE(results.objects.values_read.empty());  // kept only with the sim's truth
}

}  // namespace
}  // namespace flutterscan::session
