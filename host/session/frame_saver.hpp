#pragma once
// Saving frame files off the results thread (docs/session.md, "Output"): a
// 1080p frame's raw and fused PNGs take a few hundred ms to compress; written
// by the results thread they held the pipeline up and the line dropped frames
// (docs/benchmarks.md). One writer thread, idle-priority, and a queue bounded
// in bytes: a frame offered when it is full is not saved, and the caller counts
// it; the pipeline never waits for the disk.

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <mutex>
#include <string>
#include <thread>

#include <nlohmann/json.hpp>

#include "capture/camera_source.hpp"
#include "imaging/image.hpp"
#include "session/session_folder.hpp"

namespace flutterscan::session {

class FrameSaver {
 public:
  /// The writer thread's nice value where it cannot be SCHED_IDLE: below the workers (0).
  static constexpr int kWriterNice = 10;
  /// Frames waiting to be written hold at most this much (a 1080p RGB16 frame
  /// and its latent: 20 MB, so a dozen: a line's first frames, which come far
  /// faster than a frame's files are written, all wait their turn).
  static constexpr std::size_t kQueuedBytes = std::size_t{256} << 20;
  /// \brief Saves into `folder`, holding at most `queued_bytes` of frames waiting
  /// (and one frame, whatever its size).
  explicit FrameSaver(SessionFolder& folder, std::size_t queued_bytes = kQueuedBytes);
  ~FrameSaver();
  FrameSaver(const FrameSaver&) = delete;
  FrameSaver& operator=(const FrameSaver&) = delete;

  /// \brief What a frame and its latent hold while they wait.
  static std::size_t bytes_of(const capture::Frame& raw, const imaging::Plane& fused) {
    return raw.data.size() + fused.pixels.size() * sizeof(float);
  }
  /// \brief Whether offer() would take a frame of `bytes` now (only the writer
  /// takes frames off the queue, so for the one thread that offers, room stays room).
  bool has_room(std::size_t bytes);
  /// \brief Queues frame `sequence`'s files: the writer turns `raw` into DN
  /// (capture::frame_to_dn) and saves them (SessionFolder::save_frame); false,
  /// and nothing queued, when there is no room or finish() was called.
  bool offer(std::uint64_t sequence, capture::Frame raw, nlohmann::json descriptor,
             imaging::Plane fused);
  /// \brief Writes every frame queued, then stops the writer; returns the first
  /// frame that could not be written (its error), or empty. Idempotent.
  std::string finish();

 private:
  struct Frame {
    std::uint64_t sequence = 0;
    capture::Frame raw;
    nlohmann::json descriptor;
    imaging::Plane fused;
  };
  void write_queued();
  bool room_locked(std::size_t bytes) const;  ///< has_room(), mutex_ held

  SessionFolder& folder_;
  const std::size_t queued_limit_;
  std::size_t queued_bytes_ = 0;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<Frame> frames_;
  bool stopping_ = false;
  std::string error_;
  std::thread writer_;
};

}  // namespace flutterscan::session
