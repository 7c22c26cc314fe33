// The results stage: outcomes handled in capture order whatever order they
// come in; sightings tracked into objects, each published once; frames not
// processed logged with their flags; processed ones counted, timed and saved.
#include "session/results_stage.hpp"

#include <gtest/gtest.h>

#include "session/read_record.hpp"
#include "session/test/session_test_support.hpp"
#include "session/test/stage_test_support.hpp"

namespace flutterscan::session {
namespace {

FrameOutcome processed(std::uint64_t index, double travel_px, double position_px,
                       const std::string& value) {
  FrameOutcome o;
  o.index = index;
  o.sequence = index + 100;
  o.processed = true;
  o.travel_px = travel_px;
  o.arrival_ns = 1;
  o.log = {{"index", index}, {"model", {{"chosen", "global"}}}, {"flags", nlohmann::json::array()}};
  o.log["times_ms"] = {{"convert", 1.5}, {"deblur", 10.0}, {"decode", 4.0}};
  Sighting s;
  s.position_px = position_px;
  s.decoded = !value.empty();
  s.value = value;
  s.format = value.empty() ? "" : "Code128";
  o.sightings.push_back(s);
  o.decode_failed = value.empty();
  if (value.empty()) o.log["flags"].push_back("no-read");
  o.truth = {"ABC"};
  o.truth_in_view = {"ABC"};
  return o;
}

FrameOutcome dropped(std::uint64_t index) {
  FrameOutcome o;
  o.index = index;
  o.sequence = index + 100;
  o.log = {{"index", index}, {"flags", {"dropped"}}};
  return o;
}

// The report's previews (the first frames with a read, and failures) are made
// only when there is a report: each costs tens of ms of the results thread in
// the session's first second, when the workers need the cores.
TEST(ResultsStage, PreviewsAreMadeOnlyForAReport) {
  for (const bool report : {true, false}) {
    SCOPED_TRACE(report);
    testing::ScratchFolder scratch("results_previews");
    SessionFolder folder;
    ASSERT_EQ(folder.open(scratch.path().string(), 100), "");
    ResultsServer server;
    SessionConfig config;
    config.output.keep_first_frames = 0;
    config.output.keep_failed_frames = false;
    config.output.report = report;
    Pipeline pipeline(4);
    ResultsStage stage(config, 640, 0, pipeline, folder, server);
    for (std::uint64_t i = 0; i < 2; ++i) {
      FrameOutcome o = processed(i, 100.0 * static_cast<double>(i), 260, "ABC");
      o.frame = testing::frame_of(static_cast<int>(i));
      o.latent = imaging::Plane(4, 2, 0.5f);
      stage.take(std::move(o));
    }
    EXPECT_EQ(stage.results().previews.size(), report ? 2u : 0u);
  }
}

TEST(ResultsStage, OutcomesAreHandledInCaptureOrderAndObjectsPublishedOnce) {
  testing::ScratchFolder scratch("results_order");
  SessionFolder folder;
  ASSERT_EQ(folder.open(scratch.path().string(), 100), "");
  ResultsServer server;
  SessionConfig config;
  config.output.keep_first_frames = 0;
  config.output.keep_failed_frames = false;
  Pipeline pipeline(4);
  ResultsStage stage(config, 640, 0, pipeline, folder, server);
  // One label seen in three frames (two read, one not), then the belt moves on;
  // frame 2 was dropped. They arrive out of order.
  stage.take(processed(3, 300, 460, "ABC"));
  stage.take(processed(1, 100, 260, ""));
  stage.take(dropped(2));
  EXPECT_EQ(stage.results().latency_ms.count(), 0u);  // waiting for frame 0
  stage.take(processed(0, 0, 160, "ABC"));
  stage.finish();
  folder.close();

  const SessionResults& r = stage.results();
  EXPECT_EQ(pipeline.frames_processed, 3u);
  EXPECT_EQ(r.latency_ms.count(), 3u);
  EXPECT_DOUBLE_EQ(r.stage_ms, 3 * 15.5);  // the processed frames' stage times, not the dropped
  EXPECT_EQ(r.objects.objects, 1u);
  EXPECT_EQ(r.objects.read, 1u);
  ASSERT_EQ(r.objects.latest.size(), 1u);
  EXPECT_EQ(r.objects.latest[0].value, "ABC");
  EXPECT_EQ(r.objects.latest[0].frames_seen, 3);
  EXPECT_EQ(r.objects.latest[0].frames_decoded, 2);
  EXPECT_EQ(r.models_chosen.at("global"), 3u);
  EXPECT_EQ(r.frames_flagged.at("no-read"), 1u);
  EXPECT_EQ(r.frames_flagged.at("dropped"), 1u);
  EXPECT_EQ(r.truth_seen, std::set<std::string>{"ABC"});
  EXPECT_EQ(r.frames_saved, 0u);
  EXPECT_EQ(server.lines_sent(), 1u);  // one line per object

  int bad_lines = 0;
  const auto lines = testing::read_jsonl(scratch.path() / "session.jsonl", bad_lines);
  EXPECT_EQ(bad_lines, 0);
  // The four frames in order, then the object, finished at the end: its record
  // as the results line carried it.
  ASSERT_EQ(lines.size(), 5u);
  for (std::size_t i = 0; i < 4; ++i) EXPECT_EQ(lines[i]["index"], i);
  EXPECT_TRUE(lines[0].contains("latency_ms"));
  EXPECT_FALSE(lines[2].contains("latency_ms"));
  EXPECT_EQ(lines[4]["object_result"], read_record(r.objects.latest[0]));
  EXPECT_EQ(lines[4]["object_result"]["value"], "ABC");
}

TEST(ResultsStage, AFrameThatFailedWithoutFlagsIsLoggedAsAnError) {
  testing::ScratchFolder scratch("results_error");
  SessionFolder folder;
  ASSERT_EQ(folder.open(scratch.path().string(), 100), "");
  ResultsServer server;
  SessionConfig config;
  Pipeline pipeline(4);
  ResultsStage stage(config, 640, 0, pipeline, folder, server);
  FrameOutcome failed;
  failed.log = {{"index", 0}};
  stage.take(std::move(failed));
  stage.finish();
  folder.close();
  int bad_lines = 0;
  const auto lines = testing::read_jsonl(scratch.path() / "session.jsonl", bad_lines);
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_EQ(lines[0]["flags"], nlohmann::json::array({"error"}));
  EXPECT_EQ(stage.results().frames_flagged.count("error"), 0u);  // counted before the default
  EXPECT_EQ(pipeline.frames_processed, 0u);
}

}  // namespace
}  // namespace flutterscan::session
