#include "session/matching_stage.hpp"

#include <utility>

#include "session/frame_model.hpp"

namespace flutterscan::session {
namespace {

MatcherOptions matcher_options(double tolerance_us) {
  MatcherOptions o;
  o.tolerance_us = tolerance_us;
  return o;
}

}  // namespace

MatchingStage::MatchingStage(double tolerance_us, const OpticsConfig& optics)
    : optics_(optics), matcher_(matcher_options(tolerance_us)) {}

void MatchingStage::add_event(const ExposureRecord& event) {
  matcher_.add_event(event);
}

std::vector<MatchedFrame> MatchingStage::add_frame(capture::Frame frame) {
  const FrameStamp stamp{frame.sequence, frame.timestamp_ns, frame.host_arrival_ns};
  held_.emplace(frame.sequence, std::move(frame));
  return take_decided(matcher_.add_frame(stamp));
}

std::vector<MatchedFrame> MatchingStage::decide_waiting(std::int64_t now_ns) {
  return take_decided(matcher_.decide_waiting(now_ns));
}

std::vector<MatchedFrame> MatchingStage::flush() {
  return take_decided(matcher_.flush());
}

std::vector<nlohmann::json> MatchingStage::take_orphan_event_logs() {
  std::vector<nlohmann::json> lines;
  for (const auto& orphan : matcher_.take_orphan_events()) {
    ++events_without_frame_;
    lines.push_back(
        {{"event_without_frame",
          {{"counter", orphan.event.frame_counter}, {"start_us", orphan.event.start_us}}},
         {"why", orphan.why}});
  }
  return lines;
}

std::vector<MatchedFrame> MatchingStage::take_decided(std::vector<FrameMatch> decided) {
  std::vector<MatchedFrame> out;
  for (auto& m : decided) {
    auto frame_it = held_.find(m.frame.sequence);
    if (frame_it == held_.end()) continue;
    capture::Frame frame = std::move(frame_it->second);
    held_.erase(frame_it);
    const std::uint64_t index = next_index_++;
    if (!m.event) {
      ++frames_without_event_;
      FrameOutcome o;
      o.index = index;
      o.sequence = frame.sequence;
      o.log = {{"index", index},
               {"sequence", frame.sequence},
               {"camera_ns", frame.timestamp_ns},
               {"flags", {"no-event"}},
               {"why", m.why}};
      out.emplace_back(std::move(o));
      continue;
    }
    const double speed = belt_speed_px_per_us(*m.event, optics_);
    if (previous_event_) {
      const double previous_speed = belt_speed_px_per_us(*previous_event_, optics_);
      travel_px_ += 0.5 * (speed + previous_speed) *
                    static_cast<double>(m.event->start_us - previous_event_->start_us);
    }
    previous_event_ = m.event;
    FrameJob job;
    job.index = index;
    job.event = *m.event;
    job.residual_us = m.residual_us;
    job.travel_px = travel_px_;
    job.match_note = m.why;
    job.frame = std::move(frame);
    out.emplace_back(std::move(job));
  }
  return out;
}

}  // namespace flutterscan::session
