#include "session/frame_memory.hpp"

#include <malloc.h>
#include <sys/mman.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <vector>

namespace flutterscan::session {
namespace {

constexpr std::size_t kMib = std::size_t{1} << 20;
/// Blocks below this come from the heap and stay there when freed ...
constexpr std::size_t kMmapThreshold = 32 * kMib;
/// ... until the heap's free top exceeds this.
constexpr std::size_t kTrimThreshold = 512 * kMib;
/// What warm_frame_memory() touches at most: under the trim threshold, so that it is kept.
constexpr std::size_t kMostWarmed = 480 * kMib;
/// Bytes per pixel a frame holds besides its samples: electrons (up to 3
/// float planes), the latent (1) and room for the camera-oriented latent and
/// a window's work (1).
constexpr std::size_t kFloatPlanesPerFrame = 5;

}  // namespace

void keep_freed_frame_memory() {
  mallopt(M_MMAP_THRESHOLD, static_cast<int>(kMmapThreshold));  // glibc's largest
  mallopt(M_TRIM_THRESHOLD, static_cast<int>(kTrimThreshold));
  mallopt(M_ARENA_MAX, 1);
}

std::size_t frames_in_flight_bytes(const capture::FrameFormat& format,
                                   const ProcessingConfig& processing) {
  const auto pixels = static_cast<std::size_t>(std::max(0, format.width)) *
                      static_cast<std::size_t>(std::max(0, format.height));
  const std::size_t samples =
      format.row_bytes > 0
          ? format.row_bytes * static_cast<std::size_t>(std::max(0, format.height))
          : pixels * static_cast<std::size_t>(capture::bytes_per_pixel(format.pixel_format));
  const std::size_t frames =
      processing.queue_depth + 2 * static_cast<std::size_t>(std::max(1, processing.workers));
  return frames * (samples + kFloatPlanesPerFrame * sizeof(float) * pixels);
}

std::size_t warm_frame_memory(std::size_t bytes) {
  constexpr std::size_t kBlock = 16 * kMib;  // under the mmap threshold: heap memory
  constexpr std::uintptr_t kHugePage = 2 * kMib;
  bytes = std::min(bytes, kMostWarmed);
  std::vector<void*> blocks;
  std::size_t touched = 0;
  while (touched < bytes) {
    void* p = std::malloc(kBlock);
    if (p == nullptr) break;
    blocks.push_back(p);
    // Advice only: 512 times fewer faults where transparent huge pages are on.
    const auto begin = (reinterpret_cast<std::uintptr_t>(p) + kHugePage - 1) & ~(kHugePage - 1);
    const auto end = (reinterpret_cast<std::uintptr_t>(p) + kBlock) & ~(kHugePage - 1);
    if (end > begin) ::madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
    std::memset(p, 0, kBlock);
    touched += kBlock;
  }
  for (void* p : blocks) std::free(p);
  return touched;
}

}  // namespace flutterscan::session
