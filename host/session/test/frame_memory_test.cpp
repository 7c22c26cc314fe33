// The session's frame memory: how much its frames in flight take, and memory
// warmed before streaming that the frames then use without page faults.
#include "session/frame_memory.hpp"

#include <gtest/gtest.h>
#include <sys/resource.h>

#include <cstdlib>
#include <cstring>

namespace flutterscan::session {
namespace {

long minor_faults() {
  rusage usage{};
  getrusage(RUSAGE_THREAD, &usage);
  return usage.ru_minflt;
}

TEST(FrameMemory, FramesInFlightGrowWithTheFrameAndThePipeline) {
  capture::FrameFormat rgb16;
  rgb16.width = 1920;
  rgb16.height = 1080;
  rgb16.pixel_format = capture::PixelFormat::kRgb16;
  ProcessingConfig processing;
  processing.queue_depth = 4;
  processing.workers = 2;
  const std::size_t pixels = 1920 * 1080;
  // 8 frames: each its 6 bytes of samples and 5 float planes per pixel.
  EXPECT_EQ(frames_in_flight_bytes(rgb16, processing), 8 * (6 + 20) * pixels);
  processing.queue_depth = 8;
  EXPECT_EQ(frames_in_flight_bytes(rgb16, processing), 12 * (6 + 20) * pixels);
  capture::FrameFormat mono8 = rgb16;
  mono8.pixel_format = capture::PixelFormat::kMono8;
  EXPECT_LT(frames_in_flight_bytes(mono8, processing), frames_in_flight_bytes(rgb16, processing));
}

TEST(FrameMemory, WarmedMemoryServesTheNextPlanesWithoutPageFaults) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "AddressSanitizer's allocator quarantines freed blocks: warmed memory is not "
                  "handed out again";
#endif
  keep_freed_frame_memory();
  constexpr std::size_t kPlane = std::size_t{8} << 20;  // a 1080p float plane
  EXPECT_EQ(warm_frame_memory(std::size_t{64} << 20), std::size_t{64} << 20);
  const long before = minor_faults();
  for (int i = 0; i < 3; ++i) {
    auto* plane = static_cast<char*>(std::malloc(kPlane));
    ASSERT_NE(plane, nullptr);
    std::memset(plane, i, kPlane);
    EXPECT_EQ(plane[kPlane - 1], static_cast<char>(i));
    std::free(plane);
  }
  // Untouched memory would fault once per 4 KB page: 2048 faults per plane.
  EXPECT_LT(minor_faults() - before, 100);
  // At most what the heap keeps.
  EXPECT_LE(warm_frame_memory(std::size_t{4} << 30), std::size_t{480} << 20);
}

}  // namespace
}  // namespace flutterscan::session
