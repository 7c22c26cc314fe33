#include "session/object_tracker.hpp"

#include <algorithm>
#include <cmath>

namespace flutterscan::session {

void ObjectTracker::observe(std::uint64_t frame_index, std::uint64_t sequence, double travel_px,
                            const std::vector<Sighting>& sightings) {
  last_index_ = frame_index;
  travel_ = travel_px;
  std::vector<bool> claimed(active_.size(), false);
  for (const Sighting& s : sightings) {
    const double u = s.position_px - travel_px;
    Active* best = nullptr;
    double best_distance = match_px_;
    for (std::size_t i = 0; i < active_.size(); ++i) {
      const double distance = std::abs(active_[i].result.belt_px - u);
      if (!claimed[i] && distance <= best_distance) {
        best_distance = distance;
        best = &active_[i];
      }
    }
    if (best == nullptr) {
      Active fresh;
      fresh.result.id = next_id_++;
      fresh.result.first_frame = sequence;
      active_.push_back(std::move(fresh));
      claimed.push_back(false);
      best = &active_.back();
    }
    claimed[static_cast<std::size_t>(best - active_.data())] = true;
    ObjectResult& r = best->result;
    r.belt_px = u;
    r.last_frame = sequence;
    ++r.frames_seen;
    if (s.decoded) {
      ++r.frames_decoded;
      ++r.values[s.value];
      if (r.format.empty()) r.format = s.format;
      auto [kept, fresh] = best->best_read.try_emplace(s.value, s);
      if (!fresh && s.code.quality.grade_value > kept->second.code.quality.grade_value)
        kept->second = s;
    } else {
      r.best = s;  // the last sighting, until something reads
    }
    best->last_index = frame_index;
  }
}

ObjectResult ObjectTracker::finished(Active& active) {
  ObjectResult r = active.result;
  int best = 0;
  for (const auto& [value, count] : r.values)
    if (count > best) {
      best = count;
      r.value = value;
    }
  if (r.read()) r.best = active.best_read.at(r.value);
  return r;
}

std::vector<ObjectResult> ObjectTracker::take_finished() {
  std::vector<ObjectResult> out;
  auto gone = [&](Active& a) {
    const bool left_view = a.result.belt_px + travel_ > view_ + match_px_;
    const bool unseen = last_index_ > a.last_index + static_cast<std::uint64_t>(max_unseen_);
    return left_view || unseen;
  };
  for (auto& a : active_)
    if (gone(a)) out.push_back(finished(a));
  active_.erase(std::remove_if(active_.begin(), active_.end(), gone), active_.end());
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.id < b.id; });
  return out;
}

std::vector<ObjectResult> ObjectTracker::finish_all() {
  std::vector<ObjectResult> out;
  for (auto& a : active_) out.push_back(finished(a));
  active_.clear();
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.id < b.id; });
  return out;
}

}  // namespace flutterscan::session
