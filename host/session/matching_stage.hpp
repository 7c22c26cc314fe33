#pragma once
// The matching stage (docs/session.md, "Matching"): camera frames are held
// until the frame matcher (frame_matcher.hpp) decides them. A frame with its
// exposure event becomes a FrameJob for the workers, with the belt's travel
// since the first event (the speeds of successive events, trapezoid rule); a
// frame without one is finished here (flag no-event). Every decided frame gets
// the next index in capture order. Events no frame claimed are given back as
// session.jsonl lines. Nothing is guessed.

#include <nlohmann/json.hpp>

#include <cstdint>
#include <map>
#include <optional>
#include <variant>
#include <vector>

#include "capture/camera_source.hpp"
#include "session/frame_matcher.hpp"
#include "session/pipeline.hpp"
#include "session/session_config.hpp"

namespace flutterscan::session {

/// \brief A decided frame: a job for the workers, or (no event) an outcome already.
using MatchedFrame = std::variant<FrameJob, FrameOutcome>;

class MatchingStage {
 public:
  /// \brief Matches within `tolerance_us` of the clock fit; travel from `optics`.
  MatchingStage(double tolerance_us, const OpticsConfig& optics);

  /// \brief An exposure event from the controller (any order).
  void add_event(const ExposureRecord& event);
  /// \brief A frame from the camera (its host_arrival_ns set); returns the
  /// frames decided now, in capture order.
  std::vector<MatchedFrame> add_frame(capture::Frame frame);
  /// \brief The waiting frames decided by events that arrived since, or by
  /// waiting too long at host time `now_ns`.
  std::vector<MatchedFrame> decide_waiting(std::int64_t now_ns);
  /// \brief Every waiting frame decided (end of capture).
  std::vector<MatchedFrame> flush();
  /// \brief session.jsonl lines for the events no frame claimed since the last call.
  std::vector<nlohmann::json> take_orphan_event_logs();

  std::uint64_t frames_without_event() const { return frames_without_event_; }
  std::uint64_t events_without_frame() const { return events_without_frame_; }
  /// \brief The fit between camera and controller clocks.
  ClockRelation clocks() const { return matcher_.clocks(); }

 private:
  std::vector<MatchedFrame> take_decided(std::vector<FrameMatch> decided);

  const OpticsConfig optics_;
  FrameMatcher matcher_;
  std::map<std::uint64_t, capture::Frame> held_;  ///< by sequence, until decided
  std::uint64_t next_index_ = 0;
  std::optional<ExposureRecord> previous_event_;
  double travel_px_ = 0;
  std::uint64_t frames_without_event_ = 0;
  std::uint64_t events_without_frame_ = 0;
};

}  // namespace flutterscan::session
