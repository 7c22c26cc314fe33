#pragma once
// Matching camera frames to the controller's exposure events.
//
// Both sides count exposures: the camera's frame sequence number and the
// controller's frame counter advance once per exposure, so a frame matches the
// event whose counter is its sequence plus an offset. Their clocks are related
// by an offset and a drift, fitted by least squares over a sliding window of
// the latest matches (controller_us = a + b * camera_ns); every match is
// checked against that fit. When the counter rule and the clocks disagree (a
// counter reset, a frame the camera numbered but the controller never lit),
// the event nearest in time within the tolerance is taken and the offset
// re-derived. A frame with no event within the tolerance, and an event no
// frame claimed, are reported as such: never guessed.

#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <vector>

namespace flutterscan::session {

/// \brief One exposure event as the matcher needs it.
struct ExposureRecord {
  std::uint32_t frame_counter = 0;
  std::uint64_t start_us = 0;  ///< controller clock, start of slot 0
  std::int32_t encoder_delta = 0;
  std::uint32_t slot_time_us = 0;
  std::uint16_t slot_count = 0;
  std::uint8_t code_id = 0;
  std::uint16_t flags = 0;
};

/// \brief A frame's identity on the camera's side.
struct FrameStamp {
  std::uint64_t sequence = 0;
  std::int64_t timestamp_ns = 0;  ///< camera clock
  std::int64_t arrival_ns = 0;    ///< host steady clock, when the frame reached the host
};

/// \brief controller_us = offset_us + slope * (camera_ns - reference_ns).
struct ClockRelation {
  double offset_us = 0;
  double slope = 1e-3;  ///< controller us per camera ns (1e-3 when the clocks agree)
  std::int64_t reference_ns = 0;
  int points = 0;  ///< matches the fit rests on
  /// \brief The controller time of camera time `camera_ns`.
  double controller_us(std::int64_t camera_ns) const {
    return offset_us + slope * static_cast<double>(camera_ns - reference_ns);
  }
  /// \brief Drift of the camera clock against the controller's, parts per million.
  double drift_ppm() const { return (1e-3 / slope - 1.0) * 1e6; }
};

/// \brief Least-squares line through (camera_ns, controller_us) pairs; slope
/// 1e-3 (no drift) for a single pair.
ClockRelation fit_clocks(const std::deque<std::pair<std::int64_t, std::uint64_t>>& pairs);

struct MatcherOptions {
  std::size_t window = 32;     ///< matches in the clock fit
  double tolerance_us = 2000;  ///< largest |event start - predicted| accepted
  /// How long (host clock) a frame waits for a late event before it is
  /// declared without one. Time, not a frame count: a fast camera (or the
  /// simulator replaying frames) can deliver many frames while the event
  /// reader is merely not scheduled yet.
  std::int64_t max_wait_ns = 1'000'000'000;
  std::size_t hold_limit = 256;  ///< frames held at most (memory), whatever their age
};

/// \brief What became of one frame.
struct FrameMatch {
  FrameStamp frame;
  std::optional<ExposureRecord> event;  ///< empty: no event (see `why`)
  double residual_us = 0;               ///< event start minus the fit's prediction
  std::string why;                      ///< for a frame without event, and for a re-derived offset
};

/// \brief Events no frame claimed, reported once a later one was matched or at the end.
struct OrphanEvent {
  ExposureRecord event;
  std::string why;
};

class FrameMatcher {
 public:
  explicit FrameMatcher(MatcherOptions options = {}) : o_(options) {}

  /// \brief An event arrived (any order; duplicates ignored).
  void add_event(const ExposureRecord& event);
  /// \brief A frame arrived (increasing sequence; its arrival_ns is "now").
  /// Returns the frames decided now, in order: this one and earlier ones that
  /// waited for their event.
  std::vector<FrameMatch> add_frame(const FrameStamp& frame);
  /// \brief Decides the waiting frames whose events have arrived since, and
  /// those that have waited longer than max_wait_ns at host time `now_ns`.
  std::vector<FrameMatch> decide_waiting(std::int64_t now_ns);
  /// \brief Decides every waiting frame (end of session).
  std::vector<FrameMatch> flush();
  /// \brief Events left behind by matches since the last call (after flush(): all unclaimed).
  std::vector<OrphanEvent> take_orphan_events();

  ClockRelation clocks() const { return fit_; }
  std::size_t pending_frames() const { return pending_.size(); }

 private:
  /// Decides the waiting frames in order until one must wait longer.
  std::vector<FrameMatch> decide(std::int64_t now_ns);
  /// Decides the front frame if possible (or if `force`); false if it must wait.
  bool decide_front(bool force, std::vector<FrameMatch>& out);
  void accept(const FrameStamp& frame, const ExposureRecord& event, std::vector<FrameMatch>& out,
              std::string why);
  void orphan_events_before(std::uint32_t counter);

  MatcherOptions o_;
  std::deque<ExposureRecord> events_;  ///< unclaimed, by counter
  std::deque<FrameStamp> pending_;
  std::deque<std::pair<std::int64_t, std::uint64_t>> pairs_;
  ClockRelation fit_;
  std::optional<std::int64_t> counter_offset_;  ///< frame_counter - sequence
  std::vector<OrphanEvent> orphans_;
};

}  // namespace flutterscan::session
