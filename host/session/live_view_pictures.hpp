#pragma once
// The live view's pictures (docs/session.md, "Live view"): the latest frame
// as captured and fused, side by side, with the codes read on it. The results
// thread hands a frame over only when the picture thread is idle and the last
// pictures are old enough (LiveView decides: a few a second, never per frame);
// here, on this class's own thread at lowered priority, off the workers' and
// the results thread's path, the frame is thinned to every n-th pixel (at most
// max_width wide), its DN planes made again, the latent area-averaged to the
// same size, and both encoded as PNG (frame_preview.hpp).

#include <nlohmann/json.hpp>

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include "capture/camera_source.hpp"
#include "imaging/image.hpp"

namespace flutterscan::session {

/// \brief The pictures of one frame.
struct LivePicture {
  std::uint64_t sequence = 0;
  int width = 0, height = 0;  ///< the fused frame's size: the codes' corners are in it
  std::vector<std::uint8_t> captured_jpeg;
  std::vector<std::uint8_t> fused_jpeg;
  /// The frame's codes (text, format, corners: session.jsonl's "decoded"), flags and windows read.
  nlohmann::json about;
};

class LivePictures {
 public:
  /// \brief Pictures at most `max_width` pixels wide.
  explicit LivePictures(int max_width = 640);
  ~LivePictures();
  LivePictures(const LivePictures&) = delete;
  LivePictures& operator=(const LivePictures&) = delete;

  /// \brief No frame waiting or being encoded.
  bool idle() const;
  /// \brief Encodes `frame` and its fused `latent` on the picture thread
  /// (returns at once); `about` goes with the pictures. A frame handed over
  /// while another waits replaces it.
  void encode(capture::Frame frame, imaging::Plane latent, nlohmann::json about);
  /// \brief The latest pictures (null before the first).
  std::shared_ptr<const LivePicture> latest() const;
  /// \brief The pictures of frame `sequence` while they are among the last
  /// kKept (a page that read the state asks for the pictures it describes), else null.
  std::shared_ptr<const LivePicture> of_frame(std::uint64_t sequence) const;
  static constexpr std::size_t kKept = 3;
  /// \brief Waits until idle (tests, the end of a session).
  void wait_idle() const;
  /// \brief Pictures encoded so far, and the picture thread's CPU time on them (ms).
  std::uint64_t encoded() const;
  double encode_cpu_ms() const;

 private:
  struct Job {
    capture::Frame frame;
    imaging::Plane latent;
    nlohmann::json about;
  };
  void run();

  const int max_width_;
  mutable std::mutex mutex_;
  mutable std::condition_variable changed_;
  std::optional<Job> pending_;
  bool busy_ = false;
  bool stopping_ = false;
  std::deque<std::shared_ptr<const LivePicture>> kept_;  ///< the last kKept, newest last
  std::uint64_t encoded_ = 0;
  double encode_cpu_ms_ = 0;
  std::thread thread_;  ///< last: started once the rest is made
};

}  // namespace flutterscan::session
