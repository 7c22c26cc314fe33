#pragma once
// The live view's state (docs/session.md, "Live view"): a small snapshot of the
// running session that the results thread updates and the HTTP server
// (live_view_server.hpp) reads, each under one mutex held for microseconds:
// frame counters, processed frames per second and latency over the last
// seconds, a latency histogram, guard flags, objects read and NO-READs (all,
// and over the last minute), the latest objects' read records, a bounded ring
// of recent NO-READs, the line (controller, code, light level, scheme) and its
// state, and the latest pictures (live_view_pictures.hpp: encoded on their own
// thread, a few times a second, never per frame).

#include <nlohmann/json.hpp>

#include <array>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "session/light_probe.hpp"
#include "session/live_view_pictures.hpp"
#include "session/object_tracker.hpp"
#include "session/pipeline.hpp"
#include "session/session_config.hpp"

namespace flutterscan::session {

/// \brief The latency histogram's upper bounds, ms (Prometheus buckets; +Inf besides).
inline constexpr std::array<double, 12> kLatencyBucketsMs = {5,   10,  20,  30,  50,   75,
                                                             100, 150, 250, 500, 1000, 2500};

/// \brief What the line runs: for the page's header.
nlohmann::json live_line(const SessionConfig& config, const std::string& camera,
                         const std::string& controller,
                         const std::optional<SchemeLight>& scheme_light);

class LiveView {
 public:
  /// \brief Kept at most: the latest objects' records and the recent NO-READs.
  static constexpr std::size_t kRecentObjects = 20;
  static constexpr std::size_t kRecentNoReads = 12;

  /// \brief Pictures at most every `picture_interval_ms` (default 400: 2.5 a second).
  explicit LiveView(int picture_interval_ms = 400);

  // The session (run_session).
  /// \brief The session has started: its folder (whose files the server may
  /// serve), the line (live_line) and the state "armed".
  void begin(const std::string& folder, nlohmann::json line);
  /// \brief The controller's state as the session knows it ("armed", "disarmed").
  void set_state(const std::string& state);

  // The results thread, in capture order.
  /// \brief One frame's outcome (any kind); the frame counters of `pipeline`.
  void frame_done(const FrameOutcome& f, const Pipeline& pipeline);
  /// \brief One finished object.
  void object_done(const ObjectResult& object);
  /// \brief Takes `f`'s frame and latent for the pictures when the last ones
  /// are old enough and the picture thread is idle; otherwise leaves `f` as it is.
  void offer_picture(FrameOutcome& f);

  // The server, any thread.
  /// \brief /state.json.
  nlohmann::json state() const;
  /// \brief /metrics: Prometheus text exposition format 0.0.4.
  std::string metrics() const;
  /// \brief The session folder ("" before begin()).
  std::string folder() const;
  /// \brief The latest pictures (null before the first).
  std::shared_ptr<const LivePicture> picture() const { return pictures_.latest(); }
  /// \brief The pictures of frame `sequence`, while they are among the last few (else null).
  std::shared_ptr<const LivePicture> picture_of(std::uint64_t sequence) const {
    return pictures_.of_frame(sequence);
  }

 private:
  mutable std::mutex mutex_;
  std::string folder_;
  nlohmann::json line_ = nlohmann::json::object();
  std::string state_ = "starting";
  std::int64_t start_ns_ = 0;
  // Frames.
  std::uint64_t frames_captured_ = 0, frames_processed_ = 0, frames_dropped_ = 0,
                frames_failed_ = 0;
  std::map<std::string, std::uint64_t> flags_;
  nlohmann::json last_flags_ = nlohmann::json::array();
  std::deque<std::int64_t> processed_ns_;  ///< the last seconds' processed frames
  std::deque<double> recent_latency_ms_;   ///< the last frames' latencies
  std::array<std::uint64_t, kLatencyBucketsMs.size()> latency_buckets_{};
  std::uint64_t latency_count_ = 0;
  double latency_sum_ms_ = 0;
  // Objects.
  std::uint64_t objects_ = 0, objects_read_ = 0;
  double decode_rate_sum_ = 0;
  std::deque<std::pair<std::int64_t, bool>> last_minute_;  ///< (finished at, read)
  std::deque<nlohmann::json> recent_objects_;              ///< newest first
  std::deque<nlohmann::json> recent_no_reads_;             ///< newest first
  // Pictures.
  const std::int64_t picture_interval_ns_;
  std::int64_t last_picture_ns_ = 0;
  LivePictures pictures_;
};

}  // namespace flutterscan::session
