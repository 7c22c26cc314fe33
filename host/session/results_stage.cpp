#include "session/results_stage.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <utility>

#include "capture/frame_pixels.hpp"
#include "session/frame_preview.hpp"
#include "session/live_view.hpp"
#include "session/mqtt_publisher.hpp"
#include "session/read_record.hpp"
#include "session/session_clock.hpp"

namespace flutterscan::session {

ResultsStage::ResultsStage(const SessionConfig& config, int belt_length_px, std::int64_t start_ns,
                           Pipeline& pipeline, SessionFolder& folder, ResultsServer& server,
                           MqttPublisher* mqtt)
    : config_(config),
      start_ns_(start_ns),
      pipeline_(pipeline),
      folder_(folder),
      server_(server),
      mqtt_(mqtt),
      tracker_(belt_length_px, config.processing.object_match_px),
      saver_(folder) {}

void ResultsStage::run(const std::function<void(const Progress&)>& progress) {
  std::int64_t last_progress = 0;
  FrameOutcome o;
  while (pipeline_.outcomes.pop(o)) {
    take(std::move(o));
    const std::int64_t now = now_ns();
    if (progress && now - last_progress > 500'000'000) {
      last_progress = now;
      progress(this->progress(now));
    }
  }
  finish();
}

void ResultsStage::take(FrameOutcome outcome) {
  waiting_.emplace(outcome.index, std::move(outcome));
  for (auto it = waiting_.find(next_); it != waiting_.end(); it = waiting_.find(next_)) {
    handle(it->second);
    waiting_.erase(it);
    ++next_;
  }
}

void ResultsStage::finish() {
  publish(tracker_.finish_all());
  if (auto error = saver_.finish(); !error.empty() && results_.save_error.empty())
    results_.save_error = error;
}

void ResultsStage::handle(FrameOutcome& f) {
  if (f.log.contains("model"))
    ++results_.models_chosen[f.log["model"]["chosen"].get<std::string>()];
  if (f.log.contains("flags"))
    for (const auto& flag : f.log["flags"]) ++results_.frames_flagged[flag.get<std::string>()];
  if (f.processed)
    handle_processed(f);
  else if (!f.log.contains("flags"))
    f.log["flags"] = nlohmann::json::array({"error"});
  if (live_view_) live_view_->frame_done(f, pipeline_);
  folder_.log(f.log);
}

void ResultsStage::handle_processed(FrameOutcome& f) {
  const std::int64_t done = now_ns();
  f.latency_ms = ms_between(f.arrival_ns, done);
  f.log["latency_ms"] = std::round(f.latency_ms * 100) / 100;
  results_.latency_ms.add(f.latency_ms);
  if (const auto times = f.log.find("times_ms"); times != f.log.end() && times->is_object())
    for (const auto& [stage, ms] : times->items())
      if (ms.is_number()) results_.stage_ms += ms.get<double>();
  if (const auto motion = f.log.find("motion"); motion != f.log.end() && motion->is_object()) {
    if (motion->value("used", false)) {
      results_.refined_minus_encoder_px.add(motion->value("refined_blur_px", 0.0) -
                                            motion->value("encoder_blur_px", 0.0));
      results_.frames_speed_change += motion->contains("speed_ratio");
      results_.frames_wandering += motion->contains("block_offsets_px");
    } else if (!motion->value("edges", true))
      ++results_.frames_without_motion_edges;
  }
  count_second_pass(f.log);
  results_.processed.add(ms_between(start_ns_, done) * 1e-3);
  ++pipeline_.frames_processed;
  for (const auto& t : f.truth) results_.truth_seen.insert(t);
  for (const auto& t : f.truth_in_view) results_.truth_in_view.insert(t);
  count_truth_checks(f.truth_checks);
  bool low_grade = false;
  for (const Sighting& s : f.sightings)
    if (s.decoded) {
      ++results_.reads_by_grade[std::string(1, s.code.quality.grade)];
      low_grade = low_grade || s.code.quality.grade_value < kLowGradeValue;
    }
  const bool first = first_frames_kept_ < config_.output.keep_first_frames;
  bool keep = first || ((f.decode_failed || low_grade) && config_.output.keep_failed_frames);
  if (first) ++first_frames_kept_;
  if (keep && !saver_.has_room(FrameSaver::bytes_of(f.frame, f.latent))) {
    // The writer is this far behind: the frame goes on unsaved.
    keep = false;
    ++results_.frames_not_saved;
    f.log["files_saved"] = false;
  }
  // The report shows the first frames with a read label, and failures (made only
  // for a report: each costs tens of ms of this thread in the session's first second).
  const bool read_something = std::any_of(f.sightings.begin(), f.sightings.end(),
                                          [](const Sighting& x) { return x.decoded; });
  const bool preview = config_.output.report && ((read_something && previews_read_ < 3) ||
                                                 (f.decode_failed && previews_failed_ < 3));
  // The frame's DN planes again (it converted without them), for a preview only:
  // a kept frame's the writer makes.
  const auto dn =
      preview ? capture::frame_to_dn(f.frame) : Result<imaging::Image, std::string>::success({});
  std::string kept_frame;
  if (keep && saver_.offer(f.sequence, f.frame, f.descriptor, f.latent)) {
    ++results_.frames_saved;
    f.log["files_saved"] = true;
    kept_frame = SessionFolder::frame_file(f.sequence);
  }
  // The record's wall-clock time: now, less the time since the frame arrived.
  const std::int64_t utc_ms = std::chrono::duration_cast<std::chrono::milliseconds>(
                                  std::chrono::system_clock::now().time_since_epoch())
                                  .count() -
                              (done - f.arrival_ns) / 1'000'000;
  f.log["time"] = iso8601_utc(utc_ms);
  for (Sighting& s : f.sightings) {
    s.frame.utc_ms = utc_ms;
    s.frame.kept_frame = kept_frame;
  }
  tracker_.observe(f.index, f.sequence, f.travel_px, f.sightings);
  publish(tracker_.take_finished());
  if (preview && dn.ok()) {
    Preview p = make_preview(f.sequence, dn.value(), f.latent);
    p.caption = "frame " + std::to_string(f.sequence) +
                (f.decode_failed ? ": a label without a read" : ": labels read");
    results_.previews.push_back(std::move(p));
    (f.decode_failed ? previews_failed_ : previews_read_) += 1;
  }
  if (live_view_) live_view_->offer_picture(f);  // last: it may take the frame and latent
}

void ResultsStage::count_truth_checks(const std::vector<ReadTruthCheck>& checks) {
  ReadRecordTruth& t = results_.read_record_truth;
  for (const ReadTruthCheck& c : checks) {
    if (!c.found) {
      ++t.reads_without_label;
      continue;
    }
    ++t.reads_checked;
    t.corners_within_2px += c.corner_error_px <= 2 ? 1 : 0;
    t.modules_within_10pct += c.module_error <= 0.1 ? 1 : 0;
    t.symbology_ids_matching += c.symbology_id_matches ? 1 : 0;
    t.worst_corner_error_px = std::max(t.worst_corner_error_px, c.corner_error_px);
    t.worst_module_error = std::max(t.worst_module_error, c.module_error);
  }
}

void ResultsStage::count_second_pass(const nlohmann::json& frame_log) {
  const auto pass = frame_log.find("second_pass");
  if (pass == frame_log.end() || !pass->contains("windows")) return;
  SecondPassTally& t = results_.second_pass;
  const nlohmann::json& windows = (*pass)["windows"];
  t.frames += windows.empty() ? 0 : 1;
  for (const nlohmann::json& w : windows) {
    ++t.windows;
    t.window_ms.add(w.value("ms", 0.0));
    const nlohmann::json& read = w["read"];
    t.windows_read += read.empty() ? 0 : 1;
    t.codes_read += read.size();
    for (const nlohmann::json& value : read)
      if (t.values.size() < kSecondPassValuesKept) t.values.push_back(value.get<std::string>());
  }
  const auto skipped = pass->value("skipped", std::uint64_t{0});
  t.windows_skipped += skipped;
  t.frames_skipping += skipped > 0 ? 1 : 0;
}

void ObjectTally::add(ObjectResult object, bool with_truth) {
  ++objects;
  read += object.read() ? 1 : 0;
  decode_rate_sum += object.decode_rate();
  if (with_truth && object.read()) values_read.insert(object.value);
  latest.push_back(std::move(object));
  if (latest.size() > kObjectsListed) latest.pop_front();
}

void ResultsStage::publish(std::vector<ObjectResult> finished) {
  for (auto& o : finished) {
    nlohmann::json record = read_record(o);
    const std::string line = record.dump();
    server_.publish(line);
    if (mqtt_ != nullptr) mqtt_->publish(line);
    if (live_view_) live_view_->object_done(o);
    folder_.log({{"object_result", std::move(record)}});
    results_.objects.add(std::move(o), !results_.truth_in_view.empty());
  }
}

Progress ResultsStage::progress(std::int64_t now) const {
  Progress p;
  p.frames_captured = pipeline_.frames_captured;
  p.frames_processed = pipeline_.frames_processed;
  p.frames_dropped = pipeline_.frames_dropped;
  p.objects = results_.objects.objects;
  p.objects_read = results_.objects.read;
  p.elapsed_s = ms_between(start_ns_, now) * 1e-3;
  p.fps = p.elapsed_s > 0 ? static_cast<double>(p.frames_processed) / p.elapsed_s : 0;
  return p;
}

}  // namespace flutterscan::session
