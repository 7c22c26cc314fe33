#pragma once
// Saving frame files off the results thread (docs/session.md, "Output"): a
// 1080p frame's raw and fused PNGs take a few hundred ms to compress; written
// by the results thread they held the pipeline up and the line dropped frames
// (docs/benchmarks.md). One writer thread and a short queue: a frame offered
// while the queue is full is not saved, and the caller counts it; the pipeline
// never waits for the disk.

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <mutex>
#include <string>
#include <thread>

#include <nlohmann/json.hpp>

#include "imaging/image.hpp"
#include "session/session_folder.hpp"

namespace flutterscan::session {

class FrameSaver {
 public:
  /// The writer thread's nice value where it cannot be SCHED_IDLE: below the workers (0).
  static constexpr int kWriterNice = 10;
  /// \brief Saves into `folder`, holding at most `queued` frames waiting.
  explicit FrameSaver(SessionFolder& folder, std::size_t queued = 2);
  ~FrameSaver();
  FrameSaver(const FrameSaver&) = delete;
  FrameSaver& operator=(const FrameSaver&) = delete;

  /// \brief Whether offer() would take a frame now (only the writer takes frames
  /// off the queue, so for the one thread that offers, room stays room).
  bool has_room();
  /// \brief Queues frame `sequence`'s files (SessionFolder::save_frame); false,
  /// and nothing queued, when `queued` frames wait already or finish() was called.
  bool offer(std::uint64_t sequence, imaging::Image dn, nlohmann::json descriptor,
             imaging::Plane fused);
  /// \brief Writes every frame queued, then stops the writer; returns the first
  /// frame that could not be written (its error), or empty. Idempotent.
  std::string finish();

 private:
  struct Frame {
    std::uint64_t sequence = 0;
    imaging::Image dn;
    nlohmann::json descriptor;
    imaging::Plane fused;
  };
  void write_queued();
  bool room_locked() const;  ///< has_room(), mutex_ held

  SessionFolder& folder_;
  const std::size_t queued_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<Frame> frames_;
  bool stopping_ = false;
  std::string error_;
  std::thread writer_;
};

}  // namespace flutterscan::session
