// Frame files are written off the results thread: every frame queued is
// written by finish(); a frame offered while the short queue is full is
// refused (the caller counts it), never waited for.
#include "session/frame_saver.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <vector>

#include "session/test/session_test_support.hpp"

namespace flutterscan::session {
namespace {

imaging::Image frame_dn(int width, int height) {
  imaging::Image dn;
  for (int c = 0; c < 3; ++c) {
    dn.channels.emplace_back(width, height, 0.0f);
    for (std::size_t i = 0; i < dn.channels.back().pixels.size(); ++i)
      dn.channels.back().pixels[i] = static_cast<float>((i * 7919 + c * 104729) % 4096);
  }
  return dn;
}

TEST(FrameSaver, WritesWhatItQueuedAndRefusesWhatItCannotHoldWithoutWaiting) {
  testing::ScratchFolder scratch("frame_saver");
  SessionFolder folder;
  ASSERT_EQ(folder.open(scratch.path().string(), 1000), "");
  FrameSaver saver(folder, 1);
  // A burst of 1080p frames, each a few hundred ms to compress: one is written
  // while one waits; the rest are refused at once.
  std::vector<imaging::Image> frames;
  for (int i = 0; i < 6; ++i) frames.push_back(frame_dn(1920, 1080));
  int queued = 0, refused = 0;
  for (std::uint64_t sequence = 0; sequence < 6; ++sequence) {
    if (saver.offer(sequence, std::move(frames[sequence]), {{"sequence", sequence}},
                    imaging::Plane(1920, 1080, 0.5f)))
      ++queued;
    else
      ++refused;
  }
  EXPECT_GE(queued, 1);
  EXPECT_LE(queued, 2);
  EXPECT_EQ(queued + refused, 6);
  EXPECT_EQ(saver.finish(), "");
  int written = 0;
  for (std::uint64_t sequence = 0; sequence < 6; ++sequence) {
    const auto raw = scratch.path() / SessionFolder::frame_file(sequence);
    if (!std::filesystem::exists(raw)) continue;
    ++written;
    EXPECT_TRUE(std::filesystem::exists(scratch.path() / "frames" /
                                        (SessionFolder::frame_stem(sequence) + ".fused.png")));
  }
  EXPECT_EQ(written, queued);
  // Finished: nothing more is taken.
  EXPECT_FALSE(saver.offer(7, frame_dn(64, 64), {}, imaging::Plane(64, 64, 0.5f)));
}

}  // namespace
}  // namespace flutterscan::session
