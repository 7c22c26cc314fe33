#include "session/frame_matcher.hpp"

#include <algorithm>
#include <cmath>

namespace flutterscan::session {

ClockRelation fit_clocks(const std::deque<std::pair<std::int64_t, std::uint64_t>>& pairs) {
  ClockRelation fit;
  fit.points = static_cast<int>(pairs.size());
  if (pairs.empty()) return fit;
  fit.reference_ns = pairs.front().first;
  const double base_us = static_cast<double>(pairs.front().second);
  if (pairs.size() == 1) {
    fit.offset_us = base_us;
    return fit;
  }
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  const double n = static_cast<double>(pairs.size());
  for (const auto& [camera_ns, controller_us] : pairs) {
    const double x = static_cast<double>(camera_ns - fit.reference_ns);
    const double y = static_cast<double>(controller_us) - base_us;
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
  }
  const double denominator = n * sxx - sx * sx;
  if (denominator <= 0) {
    fit.offset_us = base_us + sy / n;
    return fit;
  }
  fit.slope = (n * sxy - sx * sy) / denominator;
  fit.offset_us = base_us + (sy - fit.slope * sx) / n;
  return fit;
}

void FrameMatcher::add_event(const ExposureRecord& event) {
  auto at = std::lower_bound(
      events_.begin(), events_.end(), event.frame_counter,
      [](const ExposureRecord& e, std::uint32_t c) { return e.frame_counter < c; });
  if (at != events_.end() && at->frame_counter == event.frame_counter) return;
  events_.insert(at, event);
}

std::vector<FrameMatch> FrameMatcher::add_frame(const FrameStamp& frame) {
  pending_.push_back(frame);
  return decide(frame.arrival_ns);
}

std::vector<FrameMatch> FrameMatcher::decide_waiting(std::int64_t now_ns) {
  return decide(now_ns);
}

std::vector<FrameMatch> FrameMatcher::decide(std::int64_t now_ns) {
  std::vector<FrameMatch> out;
  while (!pending_.empty()) {
    const bool waited_enough = now_ns - pending_.front().arrival_ns > o_.max_wait_ns;
    if (!decide_front(waited_enough || pending_.size() > o_.hold_limit, out)) break;
  }
  return out;
}

std::vector<FrameMatch> FrameMatcher::flush() {
  std::vector<FrameMatch> out;
  while (!pending_.empty()) decide_front(true, out);
  for (const auto& event : events_)
    orphans_.push_back({event, "no frame arrived for this exposure"});
  events_.clear();
  return out;
}

std::vector<OrphanEvent> FrameMatcher::take_orphan_events() {
  std::vector<OrphanEvent> out;
  out.swap(orphans_);
  return out;
}

void FrameMatcher::orphan_events_before(std::uint32_t counter) {
  while (!events_.empty() && events_.front().frame_counter < counter) {
    orphans_.push_back({events_.front(), "no frame arrived for this exposure"});
    events_.pop_front();
  }
}

void FrameMatcher::accept(const FrameStamp& frame, const ExposureRecord& event,
                          std::vector<FrameMatch>& out, std::string why) {
  FrameMatch match;
  match.frame = frame;
  match.event = event;
  match.residual_us =
      fit_.points > 0 ? static_cast<double>(event.start_us) - fit_.controller_us(frame.timestamp_ns)
                      : 0.0;
  match.why = std::move(why);
  out.push_back(std::move(match));
  counter_offset_ =
      static_cast<std::int64_t>(event.frame_counter) - static_cast<std::int64_t>(frame.sequence);
  pairs_.emplace_back(frame.timestamp_ns, event.start_us);
  while (pairs_.size() > o_.window) pairs_.pop_front();
  fit_ = fit_clocks(pairs_);
  auto it = std::find_if(events_.begin(), events_.end(), [&](const ExposureRecord& e) {
    return e.frame_counter == event.frame_counter;
  });
  if (it != events_.end()) events_.erase(it);
  orphan_events_before(event.frame_counter);
}

bool FrameMatcher::decide_front(bool force, std::vector<FrameMatch>& out) {
  const FrameStamp frame = pending_.front();
  auto no_event = [&](std::string why) {
    FrameMatch match;
    match.frame = frame;
    match.why = std::move(why);
    out.push_back(std::move(match));
    pending_.pop_front();
    return true;
  };
  if (!counter_offset_) {
    if (events_.empty())
      return force ? no_event("no exposure event arrived (controller not armed or events lost)")
                   : false;
    // The first frame of the session takes the first exposure: nothing else relates them yet.
    const ExposureRecord first = events_.front();
    pending_.pop_front();
    accept(frame, first, out, "first frame: sequence offset set");
    return true;
  }
  const std::int64_t want = static_cast<std::int64_t>(frame.sequence) + *counter_offset_;
  const double predicted = fit_.controller_us(frame.timestamp_ns);
  auto by_counter = std::find_if(events_.begin(), events_.end(), [&](const ExposureRecord& e) {
    return static_cast<std::int64_t>(e.frame_counter) == want;
  });
  if (by_counter != events_.end()) {
    const double residual = static_cast<double>(by_counter->start_us) - predicted;
    if (fit_.points < 2 || std::abs(residual) <= o_.tolerance_us) {
      const ExposureRecord event = *by_counter;
      pending_.pop_front();
      accept(frame, event, out, "");
      return true;
    }
  }
  // The counters disagree with the clocks, or the event is missing: nearest in time.
  auto nearest = events_.end();
  double best = o_.tolerance_us;
  if (fit_.points > 0) {
    for (auto it = events_.begin(); it != events_.end(); ++it) {
      const double distance = std::abs(static_cast<double>(it->start_us) - predicted);
      if (distance <= best) {
        best = distance;
        nearest = it;
      }
    }
  }
  if (nearest == events_.end()) {
    const bool later_arrived =
        !events_.empty() && static_cast<std::int64_t>(events_.back().frame_counter) > want;
    if (!later_arrived && !force) return false;  // its event may still come
    return no_event("no exposure event within " + std::to_string(o_.tolerance_us) +
                    " us of the frame's time on the controller clock (event " +
                    std::to_string(want) + " expected by sequence)");
  }
  const ExposureRecord event = *nearest;
  pending_.pop_front();
  accept(frame, event, out,
         "sequence offset re-derived: event " + std::to_string(event.frame_counter) +
             " matched by time, " + std::to_string(want) + " expected by sequence");
  return true;
}

}  // namespace flutterscan::session
