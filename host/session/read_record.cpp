#include "session/read_record.hpp"

#include <cmath>
#include <cstdio>
#include <ctime>

namespace flutterscan::session {

namespace {

/// The part of the record every sighting has: its frame.
void add_frame(const SightingFrame& f, nlohmann::json& record) {
  record["time"] = iso8601_utc(f.utc_ms);
  record["sequence"] = f.sequence;
  record["camera_ns"] = f.camera_ns;
  record["trigger"] = {{"exposure_counter", f.exposure_counter},
                       {"encoder_delta", f.encoder_delta},
                       {"travel_px", rounded(f.travel_px, 1)}};
  record["blur_px"] = rounded(f.blur_px, 2);
  if (f.encoder_blur_px && f.refined_blur_px)
    record["motion"] = {{"encoder_blur_px", rounded(*f.encoder_blur_px, 2)},
                        {"refined_blur_px", rounded(*f.refined_blur_px, 2)}};
  record["decode_ms"] = rounded(f.decode_ms, 2);
  if (!f.kept_frame.empty()) record["frame_file"] = f.kept_frame;
}

}  // namespace

double rounded(double value, int decimals) {
  const double scale = std::pow(10.0, decimals);
  return std::round(value * scale) / scale;
}

std::string iso8601_utc(std::int64_t utc_ms) {
  const std::time_t seconds =
      static_cast<std::time_t>(utc_ms >= 0 ? utc_ms / 1000 : (utc_ms - 999) / 1000);
  const int ms = static_cast<int>(utc_ms - static_cast<std::int64_t>(seconds) * 1000);
  std::tm tm{};
  gmtime_r(&seconds, &tm);
  char text[96];
  std::snprintf(text, sizeof text, "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", tm.tm_year + 1900,
                tm.tm_mon + 1, tm.tm_mday, tm.tm_hour, tm.tm_min, tm.tm_sec, ms);
  return text;
}

nlohmann::json value_json(const reader::DecodedCode& code) {
  nlohmann::json value = {{"text", code.text},
                          {"format", code.format},
                          {"decoder", code.decoder},
                          {"pass", code.pass}};
  if (!code.evidence.empty()) value["evidence"] = code.evidence;
  return value;
}

nlohmann::json code_record(const reader::DecodedCode& code) {
  const reader::CodeQuality& q = code.quality;
  nlohmann::json record;
  record["symbology_id"] = code.symbology_id;
  nlohmann::json corners = nlohmann::json::array();
  for (const reader::CodePoint& c : q.corners)
    corners.push_back({rounded(c.x, 1), rounded(c.y, 1)});
  record["corners"] = corners;
  record["orientation_deg"] = code.orientation_deg;
  if (!q.measured) {
    record["quality"] = {{"problem", q.problem}};
    return record;
  }
  record["module_px"] = rounded(q.module_px, 2);
  nlohmann::json quality = {{"grade", std::string(1, q.grade)},
                            {"grade_value", rounded(q.grade_value, 2)},
                            {"indicative", true},
                            {"symbol_contrast", rounded(q.symbol_contrast, 3)},
                            {"r_min", rounded(q.r_min, 3)},
                            {"r_max", rounded(q.r_max, 3)},
                            {"modulation", rounded(q.modulation, 3)}};
  if (reader::is_linear_format(code.format)) {
    quality["edge_contrast"] = rounded(q.edge_contrast, 3);
    quality["defects"] = rounded(q.defects, 3);
    quality["scans"] = q.scans;
  } else {
    quality["axial_nonuniformity"] = rounded(q.axial_nonuniformity, 3);
    if (!code.ec_level.empty()) quality["ec_level"] = code.ec_level;
  }
  record["quality"] = quality;
  return record;
}

nlohmann::json read_record(const ObjectResult& o) {
  nlohmann::json record = {{"object", o.id},
                           {"belt_px", rounded(o.belt_px, 1)},
                           {"first_frame", o.first_frame},
                           {"last_frame", o.last_frame},
                           {"frames", o.frames_seen},
                           {"decoded_frames", o.frames_decoded},
                           {"status", o.read() ? "READ" : "NO-READ"}};
  if (o.read()) {
    record["value"] = o.value;
    record["format"] = o.format;
  }
  if (o.values.size() > 1) {
    nlohmann::json all = nlohmann::json::object();
    for (const auto& [value, count] : o.values) all[value] = count;
    record["conflicting_values"] = all;
  }
  add_frame(o.best.frame, record);
  if (o.read()) {
    record.update(code_record(o.best.code));
    record["centre_belt_px"] = {rounded(o.best.position_px - o.best.frame.travel_px, 1),
                                rounded(o.best.across_px, 1)};
  }
  return record;
}

std::string result_line(const ObjectResult& object) {
  return read_record(object).dump();
}

}  // namespace flutterscan::session
