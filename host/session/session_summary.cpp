#include "session/session_summary.hpp"

#include <algorithm>
#include <cmath>
#include <set>

#include "imaging/deblur.hpp"
#include "session/read_record.hpp"
#include "session/results_server.hpp"

namespace flutterscan::session {

SessionCounts count_session(const Pipeline& pipeline, const MatchingStage& matching,
                            const EventInbox& inbox, const capture::CameraCounters& camera,
                            const CaptureEnd& capture_end, const SessionFolder& folder,
                            const ResultsServer& server) {
  SessionCounts counts;
  counts.frames_captured = pipeline.frames_captured;
  counts.frames_processed = pipeline.frames_processed;
  counts.frames_dropped = pipeline.frames_dropped;
  counts.frames_failed = pipeline.processing_errors;
  counts.frames_without_event = matching.frames_without_event();
  counts.events_without_frame = matching.events_without_frame();
  counts.events_received = inbox.received();
  counts.events_missing_by_counter = inbox.missing();
  counts.camera_frames_lost = camera.frames_dropped;
  counts.camera_making_ms = camera.making_ms;
  counts.clocks = matching.clocks();
  counts.stopped_by = capture_end.stopped_by;
  counts.capture_error = capture_end.error;
  counts.rotation = folder.rotation();
  counts.lines_sent = server.lines_sent();
  counts.tcp_port = server.port();
  counts.clients_dropped = server.clients_dropped();
  counts.serial_lines_lost = server.serial_lines_lost();
  return counts;
}

nlohmann::json session_summary(const SessionConfig& config, const SessionCounts& counts,
                               const SessionResults& results) {
  const ObjectTally& objects = results.objects;
  nlohmann::json s;
  s["format"] = "flutterscan-session-summary";
  s["version"] = 1;
  s["camera"] = counts.camera;
  s["controller"] = counts.controller;
  s["code"] = config.controller.code;
  if (const auto& scheme = config.controller.scheme)
    s["scheme_choice"] = {{"scheme", scheme->scheme},
                          {"expected_margin_db", scheme->margin_db},
                          {"regime_cell",
                           {{"electrons", scheme->cell_electrons},
                            {"read_noise_e", scheme->cell_read_noise},
                            {"cap", scheme->cell_cap}}}};
  if (counts.scheme_light) s["scheme_choice"]["light"] = scheme_light_json(*counts.scheme_light);
  s["method"] = processing_method_name(config.processing);
  s["frame_size"] = std::to_string(counts.format.width) + "x" +
                    std::to_string(counts.format.height) + " " +
                    capture::pixel_format_name(counts.format.pixel_format);
  s["frames_captured"] = counts.frames_captured;
  s["frames_processed"] = counts.frames_processed;
  s["frames_dropped"] = counts.frames_dropped;
  s["frames_failed"] = counts.frames_failed;
  s["frames_without_event"] = counts.frames_without_event;
  s["events_without_frame"] = counts.events_without_frame;
  s["events_received"] = counts.events_received;
  s["events_missing_by_counter"] = counts.events_missing_by_counter;
  s["camera_frames_lost"] = counts.camera_frames_lost;
  const auto n_objects = static_cast<double>(objects.objects);
  s["objects"] = objects.objects;
  s["objects_read"] = objects.read;
  s["object_read_rate"] =
      objects.objects == 0 ? 0.0 : static_cast<double>(objects.read) / n_objects;
  s["mean_decode_rate_per_object"] =
      objects.objects == 0 ? 0.0 : objects.decode_rate_sum / n_objects;
  const double duration_s = counts.duration_s;
  s["duration_s"] = std::round(duration_s * 1000) / 1000;
  s["fps"] = duration_s > 0 ? std::round(counts.frames_processed / duration_s * 10) / 10 : 0.0;
  s["latency_ms_p50"] = std::round(results.latency_ms.percentile(50) * 10) / 10;
  s["latency_ms_p99"] = std::round(results.latency_ms.percentile(99) * 10) / 10;
  // The pipeline's own capacity, whatever the camera delivered: frames a second its
  // workers could process at the stage times its frames took.
  const double stage_ms =
      counts.frames_processed == 0 ? 0.0 : results.stage_ms / counts.frames_processed;
  s["frame_stage_ms_mean"] = std::round(stage_ms * 10) / 10;
  s["capacity_fps"] =
      stage_ms > 0 ? std::round(config.processing.workers * 1000.0 / stage_ms * 10) / 10 : 0.0;
  // What a simulated camera cost the same host to make each frame (rendering).
  if (counts.camera_making_ms > 0 && counts.frames_captured > 0)
    s["camera_making_ms_mean"] =
        std::round(counts.camera_making_ms / counts.frames_captured * 10) / 10;
  // Motion refinement (processing.blur_tolerance): how far the frames moved the encoder's blur.
  const auto& delta = results.refined_minus_encoder_px;
  const auto px = [](double v) { return std::round(v * 1000) / 1000; };
  s["motion_refinement"] = {{"frames_refined", delta.count()},
                            {"frames_without_edges", results.frames_without_motion_edges},
                            {"frames_speed_change", results.frames_speed_change},
                            {"frames_wandering", results.frames_wandering},
                            {"refined_minus_encoder_px_p5", px(delta.percentile(5))},
                            {"refined_minus_encoder_px_p50", px(delta.percentile(50))},
                            {"refined_minus_encoder_px_p95", px(delta.percentile(95))}};
  if (config.processing.cascade) {
    const SecondPassTally& t = results.second_pass;
    s["cascade"] = {{"frames_with_second_pass", t.frames},
                    {"windows_second_pass", t.windows},
                    {"windows_read", t.windows_read},
                    {"codes_read", t.codes_read},
                    {"values_read_first", t.values},
                    {"windows_over_budget", t.windows_skipped},
                    {"frames_over_budget", t.frames_skipping},
                    {"window_ms_p50", std::round(t.window_ms.percentile(50) * 10) / 10},
                    {"window_ms_p99", std::round(t.window_ms.percentile(99) * 10) / 10}};
  }
  s["clock_drift_ppm"] = std::round(counts.clocks.drift_ppm() * 10) / 10;
  s["clock_fit_points"] = counts.clocks.points;
  s["stopped_by"] = counts.stopped_by;
  s["frames_saved"] = results.frames_saved;
  s["frames_not_saved"] = results.frames_not_saved;
  s["models_chosen"] = results.models_chosen;
  // By flag: saturated, misfit, blur-disagrees, no-read, ...
  s["frames_flagged"] = results.frames_flagged;
  const RotationStats& rotation = counts.rotation;
  s["rotation"] = {{"disk_budget_mb", config.output.disk_budget_mb},
                   {"frames_rotated", rotation.frames_rotated},
                   {"bytes_rotated", rotation.bytes_rotated},
                   {"frames_kept", rotation.frames_kept},
                   {"bytes_kept", rotation.bytes_kept}};
  if (rotation.frames_rotated > 0) {
    s["rotation"]["first_sequence_rotated"] = rotation.first_sequence_rotated;
    s["rotation"]["last_sequence_rotated"] = rotation.last_sequence_rotated;
  }
  s["results"] = {{"lines_sent", counts.lines_sent},
                  {"tcp_port", counts.tcp_port},
                  {"clients_dropped", counts.clients_dropped},
                  {"serial_lines_lost", counts.serial_lines_lost}};
  if (!results.truth_seen.empty()) {
    const std::set<std::string>& values = objects.values_read;
    nlohmann::json missed = nlohmann::json::array(), wrong = nlohmann::json::array();
    for (const auto& t : results.truth_seen)
      if (!values.count(t)) missed.push_back(t);
    for (const auto& v : values)
      if (!results.truth_in_view.count(v)) wrong.push_back(v);
    s["ground_truth"] = {{"labels_fully_in_view", results.truth_seen.size()},
                         {"labels_read", results.truth_seen.size() - missed.size()},
                         {"missed", missed},
                         {"wrong_values", wrong}};
    const ReadRecordTruth& r = results.read_record_truth;
    s["ground_truth"]["read_record"] = {
        {"reads_checked", r.reads_checked},
        {"reads_without_label", r.reads_without_label},
        {"corners_within_2px", r.corners_within_2px},
        {"modules_within_10pct", r.modules_within_10pct},
        {"symbology_ids_matching", r.symbology_ids_matching},
        {"worst_corner_error_px", std::round(r.worst_corner_error_px * 100) / 100},
        {"worst_module_error_pct", std::round(r.worst_module_error * 1000) / 10}};
  }
  s["reads_by_grade"] = results.reads_by_grade;
  nlohmann::json object_list = nlohmann::json::array();
  for (const auto& o : objects.latest) object_list.push_back(read_record(o));
  s["object_results"] = object_list;
  s["object_results_omitted"] = objects.objects - objects.latest.size();
  if (!counts.capture_error.empty()) s["error"] = counts.capture_error;
  if (!results.save_error.empty()) s["save_error"] = results.save_error;
  return s;
}

ReportInputs report_inputs(const nlohmann::json& summary, SessionResults& results,
                           const LedCode& code) {
  ReportInputs inputs;
  inputs.summary = summary;
  inputs.objects.assign(results.objects.latest.begin(), results.objects.latest.end());
  inputs.previews = std::move(results.previews);
  inputs.latency_ms = results.latency_ms;
  for (double rate : results.processed.per_second()) inputs.frames_per_second.add(rate);
  inputs.code = code;
  return inputs;
}

}  // namespace flutterscan::session
