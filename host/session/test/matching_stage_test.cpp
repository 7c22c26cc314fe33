// The matching stage: frames matched to their events become jobs in capture
// order with the belt's travel; frames without an event are finished there;
// events without a frame come back as log lines.
#include "session/matching_stage.hpp"

#include <gtest/gtest.h>

#include <variant>

#include "session/test/stage_test_support.hpp"

namespace flutterscan::session {
namespace {

using testing::exposure;
using testing::frame_of;

OpticsConfig optics_half_px_per_count() {
  OpticsConfig o;
  o.px_per_count = 0.5;
  return o;
}

TEST(MatchingStage, MatchedFramesBecomeJobsInOrderWithTheBeltsTravel) {
  MatchingStage matching(2000, optics_half_px_per_count());
  std::vector<FrameJob> jobs;
  for (int k = 0; k < 5; ++k) {
    matching.add_event(exposure(k));
    for (auto& m : matching.add_frame(frame_of(k))) {
      ASSERT_TRUE(std::holds_alternative<FrameJob>(m));
      jobs.push_back(std::get<FrameJob>(std::move(m)));
    }
  }
  ASSERT_EQ(jobs.size(), 5u);
  // 40 counts x 0.5 px over 52 x 100 us: 20 px per 5200 us; exposures 10 ms apart.
  const double px_per_exposure = 20.0 / 5200.0 * testing::kPeriodUs;
  for (std::size_t i = 0; i < jobs.size(); ++i) {
    EXPECT_EQ(jobs[i].index, i);
    EXPECT_EQ(jobs[i].frame.sequence, i);
    EXPECT_EQ(jobs[i].event.frame_counter, i + 1);
    EXPECT_NEAR(jobs[i].travel_px, px_per_exposure * static_cast<double>(i), 1e-9);
  }
  EXPECT_EQ(matching.frames_without_event(), 0u);
  EXPECT_TRUE(matching.flush().empty());
}

TEST(MatchingStage, AFrameWithoutItsEventIsFinishedAndCountedNotGuessed) {
  MatchingStage matching(2000, optics_half_px_per_count());
  std::vector<MatchedFrame> decided;
  for (int k = 0; k < 4; ++k) {
    if (k != 2) matching.add_event(exposure(k));
    for (auto& m : matching.add_frame(frame_of(k))) decided.push_back(std::move(m));
  }
  for (auto& m : matching.flush()) decided.push_back(std::move(m));
  ASSERT_EQ(decided.size(), 4u);
  ASSERT_TRUE(std::holds_alternative<FrameOutcome>(decided[2]));
  const FrameOutcome& without = std::get<FrameOutcome>(decided[2]);
  EXPECT_EQ(without.index, 2u);
  EXPECT_EQ(without.sequence, 2u);
  EXPECT_FALSE(without.processed);
  EXPECT_EQ(without.log["flags"], nlohmann::json::array({"no-event"}));
  EXPECT_TRUE(std::holds_alternative<FrameJob>(decided[3]));
  EXPECT_EQ(std::get<FrameJob>(decided[3]).index, 3u);
  EXPECT_EQ(matching.frames_without_event(), 1u);
}

TEST(MatchingStage, AnEventNoFrameClaimedComesBackAsALogLine) {
  MatchingStage matching(2000, optics_half_px_per_count());
  for (int k = 0; k < 4; ++k) matching.add_event(exposure(k));
  for (int k = 0; k < 4; ++k)
    if (k != 1) matching.add_frame(frame_of(k));
  matching.flush();
  const auto lines = matching.take_orphan_event_logs();
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_EQ(lines[0]["event_without_frame"]["counter"], 2);
  EXPECT_TRUE(lines[0].contains("why"));
  EXPECT_EQ(matching.events_without_frame(), 1u);
  EXPECT_TRUE(matching.take_orphan_event_logs().empty());
}

}  // namespace
}  // namespace flutterscan::session
