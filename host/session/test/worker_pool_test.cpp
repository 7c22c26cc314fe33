// The worker pool: every job taken from the bounded queue comes out as one
// outcome, and failures are counted; the queue itself never makes a producer wait.
#include "session/worker_pool.hpp"

#include <gtest/gtest.h>

#include <set>

#include "session/test/stage_test_support.hpp"

namespace flutterscan::session {
namespace {

TEST(BoundedQueue, PushFailsWhenFullAndPopEndsOnceClosedAndEmpty) {
  BoundedQueue<int> queue(2);
  int a = 1, b = 2, c = 3;
  EXPECT_TRUE(queue.try_push(std::move(a)));
  EXPECT_TRUE(queue.try_push(std::move(b)));
  EXPECT_FALSE(queue.try_push(std::move(c)));
  EXPECT_EQ(queue.size(), 2u);
  queue.close();
  int got = 0;
  ASSERT_TRUE(queue.pop(got));
  EXPECT_EQ(got, 1);
  ASSERT_TRUE(queue.pop(got));
  EXPECT_EQ(got, 2);
  EXPECT_FALSE(queue.pop(got));
}

TEST(WorkerPool, EveryJobComesOutOnceAndFailuresAreCounted) {
  SessionConfig config;
  ASSERT_EQ(check_config(config), "");
  config.processing.workers = 3;
  Pipeline pipeline(16);
  {
    WorkerPool workers(pipeline, config, nullptr);
    for (int k = 0; k < 10; ++k) {
      FrameJob job;
      job.index = static_cast<std::uint64_t>(k);
      job.frame = testing::frame_of(k);
      job.event = testing::exposure(k);
      job.event.slot_count = 3;  // not the code's length: refused at once
      ASSERT_TRUE(pipeline.jobs.try_push(std::move(job)));
    }
    pipeline.jobs.close();
    workers.join();
  }
  pipeline.outcomes.close();
  std::set<std::uint64_t> indices;
  FrameOutcome o;
  while (pipeline.outcomes.pop(o)) {
    EXPECT_FALSE(o.processed);
    EXPECT_TRUE(o.log.contains("error"));
    indices.insert(o.index);
  }
  EXPECT_EQ(indices.size(), 10u);
  EXPECT_EQ(pipeline.processing_errors, 10u);
}

}  // namespace
}  // namespace flutterscan::session
