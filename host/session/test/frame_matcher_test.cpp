// Frame-to-event matching: offset and drift fitted, missing frames and missing
// events reported (never guessed), late events waited for.
#include "session/frame_matcher.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <set>

namespace flutterscan::session {
namespace {

constexpr double kPeriodUs = 16'667;
constexpr double kDriftPpm = 80;
constexpr std::int64_t kOffsetNs = 5'000'000'000;

/// Exposure k (0-based): controller counter k + 1; camera sequence k + 3 (the
/// camera streamed 3 frames before the session).
ExposureRecord event_of(int k) {
  ExposureRecord e;
  e.frame_counter = static_cast<std::uint32_t>(k + 1);
  e.start_us = static_cast<std::uint64_t>(1000 + k * kPeriodUs + 30);  // 30 us strobe latency
  e.encoder_delta = 100;
  return e;
}

FrameStamp frame_of(int k) {
  const double controller_us = 1000 + k * kPeriodUs;
  FrameStamp f;
  f.sequence = static_cast<std::uint64_t>(k + 3);
  f.timestamp_ns = kOffsetNs + static_cast<std::int64_t>(
                                   std::llround(controller_us * 1000.0 * (1.0 + kDriftPpm * 1e-6)));
  return f;
}

TEST(ClockFit, RecoversOffsetAndDrift) {
  std::deque<std::pair<std::int64_t, std::uint64_t>> pairs;
  for (int k = 0; k < 20; ++k) pairs.emplace_back(frame_of(k).timestamp_ns, event_of(k).start_us);
  const ClockRelation fit = fit_clocks(pairs);
  EXPECT_NEAR(fit.drift_ppm(), kDriftPpm, 2.0);
  EXPECT_NEAR(fit.controller_us(frame_of(40).timestamp_ns), event_of(40).start_us, 5.0);
}

TEST(FrameMatcher, MatchesEveryFrameAndLearnsTheDrift) {
  FrameMatcher matcher;
  int matched = 0;
  for (int k = 0; k < 100; ++k) {
    matcher.add_event(event_of(k));
    for (const auto& m : matcher.add_frame(frame_of(k))) {
      ASSERT_TRUE(m.event.has_value()) << m.why;
      EXPECT_EQ(m.event->frame_counter, m.frame.sequence - 2);
      ++matched;
    }
  }
  EXPECT_EQ(matched, 100);
  EXPECT_NEAR(matcher.clocks().drift_ppm(), kDriftPpm, 5.0);
  EXPECT_TRUE(matcher.flush().empty());
  EXPECT_TRUE(matcher.take_orphan_events().empty());
}

TEST(FrameMatcher, MissingFramesLeaveTheirEventsReportedAndTheRestMatched) {
  FrameMatcher matcher;
  const std::set<int> lost_frames = {10, 11, 40};
  std::vector<FrameMatch> all;
  for (int k = 0; k < 60; ++k) {
    matcher.add_event(event_of(k));
    if (lost_frames.count(k)) continue;
    for (auto& m : matcher.add_frame(frame_of(k))) all.push_back(m);
  }
  for (auto& m : matcher.flush()) all.push_back(m);
  ASSERT_EQ(all.size(), 57u);
  for (const auto& m : all) {
    ASSERT_TRUE(m.event.has_value()) << "frame " << m.frame.sequence << ": " << m.why;
    EXPECT_EQ(m.event->frame_counter, m.frame.sequence - 2);
  }
  std::set<std::uint32_t> orphaned;
  for (const auto& o : matcher.take_orphan_events()) orphaned.insert(o.event.frame_counter);
  EXPECT_EQ(orphaned, (std::set<std::uint32_t>{11, 12, 41}));
}

TEST(FrameMatcher, MissingEventsLeaveTheirFramesWithoutEventNotGuessed) {
  FrameMatcher matcher;
  const std::set<int> lost_events = {20, 21, 50};
  std::vector<FrameMatch> all;
  for (int k = 0; k < 60; ++k) {
    if (!lost_events.count(k)) matcher.add_event(event_of(k));
    for (auto& m : matcher.add_frame(frame_of(k))) all.push_back(m);
  }
  for (auto& m : matcher.flush()) all.push_back(m);
  ASSERT_EQ(all.size(), 60u);
  std::set<std::uint64_t> without;
  for (const auto& m : all) {
    if (!m.event) {
      without.insert(m.frame.sequence);
      EXPECT_FALSE(m.why.empty());
    } else {
      EXPECT_EQ(m.event->frame_counter, m.frame.sequence - 2);
    }
  }
  EXPECT_EQ(without, (std::set<std::uint64_t>{23, 24, 53}));
  EXPECT_TRUE(matcher.take_orphan_events().empty());
}

TEST(FrameMatcher, WaitsForALateEvent) {
  FrameMatcher matcher;
  for (int k = 0; k < 5; ++k) {
    matcher.add_event(event_of(k));
    ASSERT_EQ(matcher.add_frame(frame_of(k)).size(), 1u);
  }
  EXPECT_TRUE(matcher.add_frame(frame_of(5)).empty());  // its event is not here yet
  EXPECT_EQ(matcher.pending_frames(), 1u);
  matcher.add_event(event_of(5));
  matcher.add_event(event_of(6));
  const auto decided = matcher.add_frame(frame_of(6));
  ASSERT_EQ(decided.size(), 2u);
  EXPECT_EQ(decided[0].event->frame_counter, 6u);
  EXPECT_EQ(decided[1].event->frame_counter, 7u);
}

TEST(FrameMatcher, AFastBurstOfFramesWaitsOnTheHostClockNotAFrameCount) {
  // 40 frames reach the host 0.1 ms apart (a replaying simulator, a camera's
  // backlog) while the event reader is not scheduled: none may be given up.
  FrameMatcher matcher;
  matcher.add_event(event_of(0));
  const std::int64_t t0 = 1'000'000'000;
  auto arriving = [&](int k) {
    FrameStamp f = frame_of(k);
    f.arrival_ns = t0 + k * 100'000;
    return f;
  };
  ASSERT_EQ(matcher.add_frame(arriving(0)).size(), 1u);
  for (int k = 1; k < 40; ++k) EXPECT_TRUE(matcher.add_frame(arriving(k)).empty()) << k;
  for (int k = 1; k < 40; ++k) matcher.add_event(event_of(k));
  const auto decided = matcher.decide_waiting(t0 + 5'000'000);
  ASSERT_EQ(decided.size(), 39u);
  for (const auto& m : decided) {
    ASSERT_TRUE(m.event.has_value()) << m.why;
    EXPECT_EQ(m.event->frame_counter, m.frame.sequence - 2);
  }
}

TEST(FrameMatcher, AFrameWhoseEventNeverComesIsGivenUpAfterTheWait) {
  MatcherOptions options;
  options.max_wait_ns = 200'000'000;
  FrameMatcher matcher(options);
  matcher.add_event(event_of(0));
  FrameStamp first = frame_of(0);
  first.arrival_ns = 1'000'000'000;
  ASSERT_EQ(matcher.add_frame(first).size(), 1u);
  FrameStamp second = frame_of(1);
  second.arrival_ns = 1'020'000'000;
  EXPECT_TRUE(matcher.add_frame(second).empty());
  EXPECT_TRUE(matcher.decide_waiting(1'200'000'000).empty());  // 180 ms: still waiting
  const auto decided = matcher.decide_waiting(1'230'000'000);
  ASSERT_EQ(decided.size(), 1u);
  EXPECT_FALSE(decided[0].event.has_value());
  EXPECT_NE(decided[0].why.find("no exposure event"), std::string::npos) << decided[0].why;
}

TEST(FrameMatcher, ACounterJumpIsResolvedByTheClocksAndSaidSo) {
  FrameMatcher matcher;
  for (int k = 0; k < 10; ++k) {
    matcher.add_event(event_of(k));
    matcher.add_frame(frame_of(k));
  }
  // The camera's sequence jumps by 100 (a restart of its counter) without lost exposures.
  FrameStamp f = frame_of(10);
  f.sequence += 100;
  matcher.add_event(event_of(10));
  matcher.add_event(event_of(11));
  const auto decided = matcher.add_frame(f);
  ASSERT_EQ(decided.size(), 1u);
  ASSERT_TRUE(decided[0].event.has_value());
  EXPECT_EQ(decided[0].event->frame_counter, 11u);
  EXPECT_NE(decided[0].why.find("re-derived"), std::string::npos);
}

}  // namespace
}  // namespace flutterscan::session
