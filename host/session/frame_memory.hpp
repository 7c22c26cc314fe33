#pragma once
// The memory a session's frames live in. A 1080p RGB frame passes through
// buffers of 8-25 MB (its samples, electrons, the latent) on several threads,
// and frames in flight (the queue, the workers, the results in capture order)
// hold a few hundred MB between them. Memory the process has never touched
// costs a page fault per 4 KB on first use, about 16 us each on the virtual
// machines the benchmarks run on: 30-50 ms for one fresh 8 MB plane. Left to
// itself, the allocator took the session's first second to reach the memory
// its frames need, and the frames of that second paid for it: workers 3-10
// times slower, the queue full, frames dropped (counted).

#include <cstddef>

#include "capture/camera_source.hpp"
#include "session/session_config.hpp"

namespace flutterscan::session {

/// \brief Keeps freed memory in the process (glibc: blocks up to 32 MB from the
/// heap, one heap for every thread, no trimming below 512 MB) instead of
/// returning it to the kernel: a per-thread heap was unmapped whenever its
/// last frame left it, and the next frame's planes came back as page faults.
/// run_session() calls it; a benchmark of the same work calls it too.
void keep_freed_frame_memory();

/// \brief The memory a session's frames in flight take at most, about: per
/// frame its samples, its electrons, the motion frame and the latent, for the
/// queue's frames, the workers' and as many again on their way to the results.
std::size_t frames_in_flight_bytes(const capture::FrameFormat& format,
                                   const ProcessingConfig& processing);

/// \brief Touches `bytes` of heap memory once and frees it (kept, after
/// keep_freed_frame_memory()), in blocks advised for huge pages where the kernel
/// offers them: the frames that follow land on memory already mapped. At most
/// the trim threshold (512 MB); returns the bytes touched.
std::size_t warm_frame_memory(std::size_t bytes);

}  // namespace flutterscan::session
