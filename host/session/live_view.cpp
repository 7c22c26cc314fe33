#include "session/live_view.hpp"

#include <algorithm>
#include <cstdio>
#include <sstream>
#include <utility>
#include <vector>

#include "session/read_record.hpp"
#include "session/session_clock.hpp"
#include "session/value_distribution.hpp"

namespace flutterscan::session {

namespace {

constexpr std::int64_t kFpsWindowNs = 2'000'000'000;  // processed frames per second over 2 s
constexpr std::int64_t kMinuteNs = 60'000'000'000;    // read rate over the last minute
constexpr std::size_t kRecentLatencies = 240;         // p50 and p99 of the last frames

double share(std::uint64_t part, std::uint64_t whole) {
  return whole > 0 ? static_cast<double>(part) / static_cast<double>(whole) : 0.0;
}

/// A Prometheus sample value: integers as integers, others with enough digits.
std::string number(double value) {
  char text[40];
  std::snprintf(text, sizeof text, "%.9g", value);
  return text;
}

/// A Prometheus label value: backslash, double quote and newline escaped.
std::string label_value(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (c == '\\' || c == '"')
      out += {'\\', c};
    else if (c == '\n')
      out += "\\n";
    else
      out += c;
  }
  return out;
}

/// Processed frames per second over the window, once it holds two frames; 0
/// when the last is older than the window.
double frames_per_second(const std::deque<std::int64_t>& processed_ns, std::int64_t now) {
  if (processed_ns.size() < 2 || now - processed_ns.back() > kFpsWindowNs) return 0;
  return static_cast<double>(processed_ns.size() - 1) /
         (ms_between(processed_ns.front(), processed_ns.back()) * 1e-3);
}

}  // namespace

nlohmann::json live_line(const SessionConfig& config, const std::string& camera,
                         const std::string& controller,
                         const std::optional<SchemeLight>& scheme_light) {
  nlohmann::json line = {{"camera", camera},
                         {"controller", controller},
                         {"code", config.controller.code},
                         {"method", processing_method_name(config.processing)}};
  if (const auto& scheme = config.controller.scheme)
    line["scheme"] = {{"scheme", scheme->scheme}, {"expected_margin_db", scheme->margin_db}};
  if (scheme_light) line["light"] = describe_scheme_light(*scheme_light);
  return line;
}

LiveView::LiveView(int picture_interval_ms)
    : picture_interval_ns_(static_cast<std::int64_t>(picture_interval_ms) * 1'000'000) {}

void LiveView::begin(const std::string& folder, nlohmann::json line) {
  std::lock_guard lock(mutex_);
  folder_ = folder;
  line_ = std::move(line);
  state_ = "armed";
  start_ns_ = now_ns();
}

void LiveView::set_state(const std::string& state) {
  std::lock_guard lock(mutex_);
  state_ = state;
}

void LiveView::frame_done(const FrameOutcome& f, const Pipeline& pipeline) {
  const std::int64_t now = now_ns();
  std::lock_guard lock(mutex_);
  frames_captured_ = pipeline.frames_captured;
  frames_processed_ = pipeline.frames_processed;
  frames_dropped_ = pipeline.frames_dropped;
  frames_failed_ = pipeline.processing_errors;
  last_flags_ = f.log.value("flags", nlohmann::json::array());
  for (const auto& flag : last_flags_)
    if (flag.is_string()) ++flags_[flag.get<std::string>()];
  if (!f.processed) return;
  processed_ns_.push_back(now);
  while (now - processed_ns_.front() > kFpsWindowNs) processed_ns_.pop_front();
  recent_latency_ms_.push_back(f.latency_ms);
  if (recent_latency_ms_.size() > kRecentLatencies) recent_latency_ms_.pop_front();
  for (std::size_t b = 0; b < kLatencyBucketsMs.size(); ++b)
    if (f.latency_ms <= kLatencyBucketsMs[b]) ++latency_buckets_[b];
  ++latency_count_;
  latency_sum_ms_ += f.latency_ms;
}

void LiveView::object_done(const ObjectResult& object) {
  nlohmann::json record = read_record(object);
  const std::int64_t now = now_ns();
  std::lock_guard lock(mutex_);
  ++objects_;
  objects_read_ += object.read() ? 1 : 0;
  decode_rate_sum_ += object.decode_rate();
  last_minute_.emplace_back(now, object.read());
  while (now - last_minute_.front().first > kMinuteNs) last_minute_.pop_front();
  if (!object.read()) {
    recent_no_reads_.push_front(record);
    if (recent_no_reads_.size() > kRecentNoReads) recent_no_reads_.pop_back();
  }
  recent_objects_.push_front(std::move(record));
  if (recent_objects_.size() > kRecentObjects) recent_objects_.pop_back();
}

void LiveView::offer_picture(FrameOutcome& f) {
  const std::int64_t now = now_ns();
  {
    std::lock_guard lock(mutex_);
    if (now - last_picture_ns_ < picture_interval_ns_ || !pictures_.idle()) return;
    last_picture_ns_ = now;
  }
  nlohmann::json about = {{"decoded", f.log.value("decoded", nlohmann::json::array())},
                          {"flags", f.log.value("flags", nlohmann::json::array())},
                          {"windows", f.log.value("decode_windows", 0)}};
  pictures_.encode(std::move(f.frame), std::move(f.latent), std::move(about));
}

nlohmann::json LiveView::state() const {
  const std::int64_t now = now_ns();
  const auto picture = pictures_.latest();
  std::lock_guard lock(mutex_);
  nlohmann::json s;
  s["state"] = state_;
  s["folder"] = folder_;
  s["line"] = line_;
  s["elapsed_s"] = start_ns_ > 0 ? rounded(ms_between(start_ns_, now) * 1e-3, 1) : 0.0;
  s["frames"] = {{"captured", frames_captured_},
                 {"processed", frames_processed_},
                 {"dropped", frames_dropped_},
                 {"failed", frames_failed_}};
  s["fps"] = rounded(frames_per_second(processed_ns_, now), 1);
  const std::vector<double> latencies(recent_latency_ms_.begin(), recent_latency_ms_.end());
  s["latency_ms"] = {{"last", latencies.empty() ? 0.0 : rounded(latencies.back(), 1)},
                     {"p50", rounded(percentile(latencies, 50), 1)},
                     {"p99", rounded(percentile(latencies, 99), 1)}};
  s["flags"] = flags_;
  s["last_flags"] = last_flags_;
  std::uint64_t minute = 0, minute_read = 0;
  for (const auto& [at, read] : last_minute_)
    if (now - at <= kMinuteNs) {
      ++minute;
      minute_read += read ? 1 : 0;
    }
  s["objects"] = {{"total", objects_},
                  {"read", objects_read_},
                  {"no_read", objects_ - objects_read_},
                  {"read_rate", rounded(share(objects_read_, objects_), 4)},
                  {"mean_decode_rate", rounded(objects_ > 0 ? decode_rate_sum_ / objects_ : 0, 4)},
                  {"last_minute",
                   {{"total", minute},
                    {"read", minute_read},
                    {"read_rate", rounded(share(minute_read, minute), 4)}}}};
  s["recent_objects"] = nlohmann::json(recent_objects_);
  s["no_reads"] = nlohmann::json(recent_no_reads_);
  const std::uint64_t encoded = pictures_.encoded();
  s["live_view"] = {
      {"pictures", encoded},
      {"picture_cpu_ms_mean", rounded(encoded > 0 ? pictures_.encode_cpu_ms() / encoded : 0, 2)}};
  if (picture)
    s["picture"] = {{"sequence", picture->sequence},
                    {"width", picture->width},
                    {"height", picture->height},
                    {"about", picture->about}};
  else
    s["picture"] = nullptr;
  return s;
}

std::string LiveView::metrics() const {
  const std::int64_t now = now_ns();
  std::lock_guard lock(mutex_);
  std::ostringstream m;
  auto family = [&](const char* name, const char* type, const char* help) {
    m << "# HELP " << name << ' ' << help << "\n# TYPE " << name << ' ' << type << '\n';
  };
  family("flutterscan_frames_captured_total", "counter", "Frames the camera delivered.");
  m << "flutterscan_frames_captured_total " << frames_captured_ << '\n';
  family("flutterscan_frames_processed_total", "counter", "Frames deblurred and decoded.");
  m << "flutterscan_frames_processed_total " << frames_processed_ << '\n';
  family("flutterscan_frames_dropped_total", "counter",
         "Frames dropped because processing was behind.");
  m << "flutterscan_frames_dropped_total " << frames_dropped_ << '\n';
  family("flutterscan_frames_failed_total", "counter", "Frames that could not be processed.");
  m << "flutterscan_frames_failed_total " << frames_failed_ << '\n';
  family("flutterscan_frames_flagged_total", "counter", "Frames by guard flag.");
  for (const auto& [flag, count] : flags_)
    m << "flutterscan_frames_flagged_total{flag=\"" << label_value(flag) << "\"} " << count << '\n';
  family("flutterscan_reads_total", "counter", "Objects read.");
  m << "flutterscan_reads_total " << objects_read_ << '\n';
  family("flutterscan_no_reads_total", "counter", "Objects finished without a read (NO-READ).");
  m << "flutterscan_no_reads_total " << objects_ - objects_read_ << '\n';
  family("flutterscan_frame_latency_seconds", "histogram",
         "Frame arrival to its result, processed frames.");
  for (std::size_t b = 0; b < kLatencyBucketsMs.size(); ++b)
    m << "flutterscan_frame_latency_seconds_bucket{le=\"" << number(kLatencyBucketsMs[b] * 1e-3)
      << "\"} " << latency_buckets_[b] << '\n';
  m << "flutterscan_frame_latency_seconds_bucket{le=\"+Inf\"} " << latency_count_ << '\n'
    << "flutterscan_frame_latency_seconds_sum " << number(latency_sum_ms_ * 1e-3) << '\n'
    << "flutterscan_frame_latency_seconds_count " << latency_count_ << '\n';
  family("flutterscan_fps", "gauge", "Frames processed per second over the last 2 s.");
  m << "flutterscan_fps " << number(frames_per_second(processed_ns_, now)) << '\n';
  return m.str();
}

std::string LiveView::folder() const {
  std::lock_guard lock(mutex_);
  return folder_;
}

}  // namespace flutterscan::session
