// Frame files are written off the results thread: every frame queued is
// written by finish(); a frame offered while the queue's bytes are taken is
// refused (the caller counts it), never waited for.
#include "session/frame_saver.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <vector>

#include "session/test/session_test_support.hpp"

namespace flutterscan::session {
namespace {

/// A 12-bit RGB16 camera frame of varied samples.
capture::Frame raw_frame(int width, int height) {
  capture::Frame frame;
  frame.format = {width, height, capture::PixelFormat::kRgb16, 12,
                  static_cast<std::size_t>(width) * 6};
  frame.data.resize(frame.format.row_bytes * static_cast<std::size_t>(height));
  for (std::size_t i = 0; i + 1 < frame.data.size(); i += 2) {
    const std::size_t v = (i * 7919) % 4096;
    frame.data[i] = static_cast<std::uint8_t>(v & 0xff);
    frame.data[i + 1] = static_cast<std::uint8_t>(v >> 8);
  }
  return frame;
}

int frames_written(const std::filesystem::path& folder, std::uint64_t offered) {
  int written = 0;
  for (std::uint64_t sequence = 0; sequence < offered; ++sequence) {
    if (!std::filesystem::exists(folder / SessionFolder::frame_file(sequence))) continue;
    ++written;
    EXPECT_TRUE(std::filesystem::exists(folder / "frames" /
                                        (SessionFolder::frame_stem(sequence) + ".fused.png")));
  }
  return written;
}

TEST(FrameSaver, WritesWhatItQueuedAndRefusesWhatItCannotHoldWithoutWaiting) {
  testing::ScratchFolder scratch("frame_saver");
  SessionFolder folder;
  ASSERT_EQ(folder.open(scratch.path().string(), 1000), "");
  const imaging::Plane latent(1920, 1080, 0.5f);
  const std::size_t one = FrameSaver::bytes_of(raw_frame(1920, 1080), latent);
  EXPECT_EQ(one, 1920u * 1080 * 6 + 1920u * 1080 * 4);
  FrameSaver saver(folder, one + one / 2);
  // A burst of 1080p frames, each a few hundred ms to compress: one is written
  // while one waits; the rest are refused at once.
  int queued = 0, refused = 0;
  for (std::uint64_t sequence = 0; sequence < 6; ++sequence) {
    const bool room = saver.has_room(one);
    const bool taken =
        saver.offer(sequence, raw_frame(1920, 1080), {{"sequence", sequence}}, latent);
    EXPECT_TRUE(taken || !room) << sequence;  // for the one offering thread, room stays room
    (taken ? queued : refused) += 1;
  }
  EXPECT_GE(queued, 1);
  EXPECT_LE(queued, 2);
  EXPECT_EQ(queued + refused, 6);
  EXPECT_EQ(saver.finish(), "");
  EXPECT_EQ(frames_written(scratch.path(), 6), queued);
  // Finished: nothing more is taken.
  EXPECT_FALSE(saver.offer(7, raw_frame(64, 64), {}, imaging::Plane(64, 64, 0.5f)));
}

// A line's first frames arrive far faster than their files are written: within
// the queue's bytes they all wait their turn and are written.
TEST(FrameSaver, ALinesFirstFramesAllWaitWithinTheQueuesBytes) {
  testing::ScratchFolder scratch("frame_saver_first");
  SessionFolder folder;
  ASSERT_EQ(folder.open(scratch.path().string(), 1000), "");
  FrameSaver saver(folder);
  const imaging::Plane latent(640, 480, 0.5f);
  for (std::uint64_t sequence = 0; sequence < 10; ++sequence)
    EXPECT_TRUE(saver.offer(sequence, raw_frame(640, 480), {{"sequence", sequence}}, latent));
  EXPECT_EQ(saver.finish(), "");
  EXPECT_EQ(frames_written(scratch.path(), 10), 10);
}

// A frame the writer cannot turn into DN is reported by finish(), naming it.
TEST(FrameSaver, AFrameThatCannotBeConvertedIsReported) {
  testing::ScratchFolder scratch("frame_saver_bad");
  SessionFolder folder;
  ASSERT_EQ(folder.open(scratch.path().string(), 1000), "");
  FrameSaver saver(folder);
  capture::Frame truncated = raw_frame(64, 64);
  truncated.sequence = 3;
  truncated.data.resize(100);
  EXPECT_TRUE(saver.offer(3, truncated, {}, imaging::Plane(64, 64, 0.5f)));
  const std::string error = saver.finish();
  EXPECT_NE(error, "");
  EXPECT_FALSE(std::filesystem::exists(scratch.path() / SessionFolder::frame_file(3)));
}

}  // namespace
}  // namespace flutterscan::session
