#include "session/session.hpp"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <malloc.h>

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <ctime>
#include <deque>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <sstream>
#include <thread>

#include "capture/camera_source.hpp"
#include "capture/frame_pixels.hpp"
#include "device/controller_client.hpp"
#include "device/in_process_transport.hpp"
#include "device/usb_discovery.hpp"
#include "device/virtual_controller.hpp"
#include "imaging/bayer.hpp"
#include "imaging/capture_descriptor.hpp"
#include "imaging/deblur.hpp"
#include "imaging/flat_field.hpp"
#include "imaging/motion_frame.hpp"
#include "imaging/row_fft.hpp"
#include "session/barcode_reader.hpp"
#include "session/frame_matcher.hpp"
#include "session/frame_model.hpp"
#include "session/light_probe.hpp"
#include "session/line_devices.hpp"
#include "session/model_fit.hpp"
#include "session/object_tracker.hpp"
#include "session/results_server.hpp"
#include "session/session_folder.hpp"
#include "session/session_report.hpp"

namespace flutterscan::session {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

std::int64_t now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now().time_since_epoch())
      .count();
}

double ms_between(std::int64_t from_ns, std::int64_t to_ns) {
  return static_cast<double>(to_ns - from_ns) * 1e-6;
}

/// A frame matched to its event, on its way to a worker.
struct FrameJob {
  std::uint64_t index = 0;
  capture::Frame frame;
  ExposureRecord event;
  double residual_us = 0;
  double travel_px = 0;
  std::string match_note;
};

/// What the results thread gets for every frame index, processed or not.
struct FrameOutcome {
  std::uint64_t index = 0;
  std::uint64_t sequence = 0;
  bool processed = false;
  nlohmann::json log;
  std::vector<Sighting> sightings;
  double travel_px = 0;
  bool decode_failed = false;
  double latency_ms = 0;
  std::int64_t arrival_ns = 0;
  // Kept only for frames whose files are saved.
  capture::Frame frame;  ///< as captured (the DN planes are made again only to save or show it)
  imaging::Plane latent;
  nlohmann::json descriptor;
  std::vector<std::string> truth;
  std::vector<std::string> truth_in_view;
};

/// A queue with a capacity: push never waits, it fails when full.
template <typename T>
class BoundedQueue {
 public:
  explicit BoundedQueue(std::size_t capacity) : capacity_(capacity) {}
  bool try_push(T&& item) {
    std::lock_guard lock(mutex_);
    if (items_.size() >= capacity_) return false;
    items_.push_back(std::move(item));
    ready_.notify_one();
    return true;
  }
  void push(T&& item) {  // unbounded use (results): never fails
    std::lock_guard lock(mutex_);
    items_.push_back(std::move(item));
    ready_.notify_one();
  }
  /// Waits for an item; false once closed and empty.
  bool pop(T& item) {
    std::unique_lock lock(mutex_);
    ready_.wait(lock, [&] { return !items_.empty() || closed_; });
    if (items_.empty()) return false;
    item = std::move(items_.front());
    items_.pop_front();
    return true;
  }
  void close() {
    std::lock_guard lock(mutex_);
    closed_ = true;
    ready_.notify_all();
  }

 private:
  std::size_t capacity_;
  std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<T> items_;
  bool closed_ = false;
};

double percentile(std::vector<double> values, double p) {
  if (values.empty()) return 0;
  std::sort(values.begin(), values.end());
  const double rank = p / 100.0 * static_cast<double>(values.size() - 1);
  const auto lo = static_cast<std::size_t>(std::floor(rank));
  const auto hi = std::min(lo + 1, values.size() - 1);
  return values[lo] + (values[hi] - values[lo]) * (rank - static_cast<double>(lo));
}

std::string session_folder_name(const OutputConfig& output) {
  if (!output.timestamped_subfolder) return output.dir;
  const std::time_t t = std::time(nullptr);
  std::tm local{};
  localtime_r(&t, &local);
  char stamp[32];
  std::strftime(stamp, sizeof stamp, "%Y%m%d-%H%M%S", &local);
  std::string base = (fs::path(output.dir) / stamp).string();
  std::string name = base;
  for (int n = 2; fs::exists(name); ++n) name = base + "-" + std::to_string(n);
  return name;
}

/// The position along the motion, mirrored so that objects move toward larger values.
double along_motion(double x, double y, int width, int height, imaging::Direction d) {
  switch (d) {
    case imaging::Direction::kPlusX:
      return x;
    case imaging::Direction::kMinusX:
      return width - 1 - x;
    case imaging::Direction::kPlusY:
      return y;
    case imaging::Direction::kMinusY:
      return height - 1 - y;
  }
  return x;
}

/// PNG bytes for the report: the raw frame stretched to 8 bits (display only) and the latent.
Preview make_preview(const FrameOutcome& o, const imaging::Image& dn) {
  Preview p;
  p.sequence = o.sequence;
  // Display only: the brightest sample maps to white.
  float brightest = 1;
  for (const auto& plane : dn.channels)
    for (float v : plane.pixels) brightest = std::max(brightest, v);
  const double scale = 255.0 / brightest;
  const int width = dn.width(), height = dn.height();
  const int out_width = std::min(width, 960);
  const double shrink = static_cast<double>(out_width) / width;
  cv::Mat before;
  if (dn.channel_count() == 3) {
    std::vector<cv::Mat> planes;
    for (int c = 2; c >= 0; --c) {
      cv::Mat plane(height, width, CV_32F,
                    const_cast<float*>(dn.channels[static_cast<std::size_t>(c)].pixels.data()));
      cv::Mat bytes;
      plane.convertTo(bytes, CV_8U, scale);
      planes.push_back(bytes);
    }
    cv::merge(planes, before);
  } else {
    cv::Mat plane(height, width, CV_32F, const_cast<float*>(dn.channels[0].pixels.data()));
    plane.convertTo(before, CV_8U, scale);
  }
  cv::Mat latent(o.latent.height, o.latent.width, CV_32F,
                 const_cast<float*>(o.latent.pixels.data()));
  cv::Mat after;
  latent.convertTo(after, CV_8U, 255.0);
  if (shrink < 1) {
    cv::resize(before, before, cv::Size(), shrink, shrink, cv::INTER_AREA);
    cv::resize(after, after, cv::Size(), shrink, shrink, cv::INTER_AREA);
  }
  cv::imencode(".png", before, p.before_png);
  cv::imencode(".png", after, p.after_png);
  return p;
}

/// Everything the threads share.
struct Shared {
  explicit Shared(const SessionConfig& c) : config(c), jobs(c.processing.queue_depth) {}
  const SessionConfig& config;
  BoundedQueue<FrameJob> jobs;
  BoundedQueue<FrameOutcome> outcomes{1u << 30};
  std::atomic<std::uint64_t> frames_captured{0};
  std::atomic<std::uint64_t> frames_dropped{0};
  std::atomic<std::uint64_t> frames_processed{0};
  std::atomic<std::uint64_t> processing_errors{0};
};

/// Blurs up to this long deblur with FFT plans measured before the session
/// streams (longer ones with estimated plans, about 20% slower).
constexpr int kLongestPlannedBlurPx = 256;

/// Worker: descriptor, deblur and fusion, decoding, sightings.
FrameOutcome process(FrameJob& job, const SessionConfig& config, std::atomic<double>& last_blur_px,
                     const imaging::FlatField* flat) {
  FrameOutcome out;
  out.index = job.index;
  out.sequence = job.frame.sequence;
  out.travel_px = job.travel_px;
  out.arrival_ns = job.frame.host_arrival_ns;
  out.truth = job.frame.truth;
  out.truth_in_view = job.frame.truth_in_view;
  const std::int64_t t0 = now_ns();
  nlohmann::json flags = nlohmann::json::array();
  nlohmann::json& log = out.log;
  log = {{"index", job.index},
         {"sequence", job.frame.sequence},
         {"camera_ns", job.frame.timestamp_ns},
         {"event",
          {{"counter", job.event.frame_counter},
           {"start_us", job.event.start_us},
           {"encoder_delta", job.event.encoder_delta},
           {"code_id", job.event.code_id},
           {"slot_time_us", job.event.slot_time_us},
           {"flags", job.event.flags}}},
         {"clock_residual_us", std::round(job.residual_us * 10) / 10},
         {"method", imaging::method_name(config.processing.method)}};
  if (!job.match_note.empty()) log["match_note"] = job.match_note;
  // A blur the encoder implies but the frame cannot hold: flagged, counted, the session goes on.
  if (auto problem = blur_out_of_range(job.event, config.optics, job.frame.format);
      !problem.empty()) {
    log["error"] = problem;
    log["flags"] = nlohmann::json::array({"blur-out-of-range"});
    return out;
  }
  auto model = frame_model(job.event, config.controller.parsed_code, config, job.frame.format);
  auto converted = model.ok() ? capture::frame_to_electrons(job.frame, model.value())
                              : Result<capture::ElectronFrame, std::string>::failure(model.error());
  if (!converted.ok()) {
    log["error"] = converted.error();
    flags.push_back("error");
    log["flags"] = flags;
    return out;
  }
  log["blur_px"] = std::round(model.value().blur_px * 100) / 100;
  const std::int64_t t1 = now_ns();
  imaging::DeblurOptions options;
  options.method = config.processing.method;
  options.threads = config.processing.threads_per_worker;
  options.plan_effort = imaging::PlanEffort::kMeasuredIfKnown;  // measured before streaming
  imaging::Image& electrons = converted.value().electrons;
  if (flat != nullptr && !model.value().bayer_rggb) {
    if (auto problem = imaging::apply_flat_field(electrons, *flat); !problem.empty()) {
      log["error"] = "optics.flat_field: " + problem;
      flags.push_back("error");
      log["flags"] = flags;
      return out;
    }
  }
  // The simplest model that fits the frame, and the guards (model_fit.hpp); raw
  // Bayer frames keep the grey global model on their raw planes.
  imaging::Plane latent;
  std::string deblur_error;
  if (model.value().bayer_rggb) {
    auto r = imaging::deblur_bayer(electrons.channels[0], model.value(), options,
                                   imaging::BayerMode::kRawPlanes);
    if (r.ok())
      latent = std::move(r.value().latent);
    else
      deblur_error = r.error();
  } else {
    ModelFitConfig fit;
    fit.encoder = config.optics.encoder;
    fit.choose_latent = config.processing.choose_model;
    fit.line_time_us = config.optics.line_time_us;
    fit.slot_time_us = job.event.slot_time_us;
    fit.blur_check_every = config.processing.blur_check_every;
    fit.fallback_blur_px = last_blur_px.load();
    auto r = deblur_fitting_model(converted.value().saturated_share, electrons, model.value(),
                                  options, fit, job.index);
    if (r.ok()) {
      if (r.value().estimated_blur_px > 0) last_blur_px.store(r.value().estimated_blur_px);
      latent = std::move(r.value().latent);
      for (const auto& flag : r.value().flags) flags.push_back(flag);
      log.update(r.value().log);
      if (r.value().log.contains("model"))
        model.value().blur_px = r.value().log["model"]["blur_px"].get<double>();
    } else {
      deblur_error = r.error();
    }
  }
  const std::int64_t t2 = now_ns();
  if (!deblur_error.empty()) {
    log["error"] = deblur_error;
    flags.push_back("error");
    log["flags"] = flags;
    return out;
  }
  // Paper along the motion: where codes are looked for (processing.decode_area) and
  // the labels judged (read, or NO-READ).
  const imaging::Direction direction = model.value().direction;
  const std::vector<LabelRegion> paper =
      find_paper_runs(imaging::to_motion_frame(latent, direction));
  const bool labels_only = config.processing.decode_area == DecodeArea::kLabels;
  const std::vector<DecodeWindow> windows =
      labels_only ? decode_windows(paper, latent.width, latent.height, direction)
                  : std::vector<DecodeWindow>{};
  BarcodeReadout readout;
  if (!labels_only || !windows.empty())
    readout =
        read_barcodes(latent, config.processing.symbologies, config.processing.try_rotate, windows);
  if (labels_only) log["decode_windows"] = windows.size();
  const std::vector<DecodedCode>& codes = readout.codes;
  if (!readout.decoder_fault.empty()) {
    // ZXing failed an internal assertion on this image: nothing read, the session goes on.
    log["decoder_fault"] = readout.decoder_fault;
    flags.push_back("decoder-fault");
  }
  std::vector<LabelRegion> regions = paper;
  // A label cut by the frame is not judged; near the upstream edge the deblurred
  // image has no support: no judging there either.
  const double upstream = model.value().blur_px + 4;
  std::erase_if(regions, [&](const LabelRegion& r) { return r.cut || r.begin < upstream; });
  const std::int64_t t3 = now_ns();

  std::vector<bool> used(codes.size(), false);
  nlohmann::json decoded = nlohmann::json::array();
  for (std::size_t i = 0; i < codes.size(); ++i)
    decoded.push_back({{"text", codes[i].text},
                       {"format", codes[i].format},
                       {"x", std::lround(codes[i].centre_x)},
                       {"y", std::lround(codes[i].centre_y)}});
  for (const LabelRegion& r : regions) {
    bool any = false;
    for (std::size_t i = 0; i < codes.size(); ++i) {
      const double p = along_motion(codes[i].centre_x, codes[i].centre_y, latent.width,
                                    latent.height, direction);
      if (p >= r.begin - 8 && p <= r.end + 8 && !used[i]) {
        used[i] = true;
        any = true;
        out.sightings.push_back({p, true, codes[i].text, codes[i].format});
      }
    }
    if (!any) {
      out.sightings.push_back({0.5 * (r.begin + r.end), false, "", ""});
      out.decode_failed = true;
    }
  }
  for (std::size_t i = 0; i < codes.size(); ++i)
    if (!used[i])
      out.sightings.push_back({along_motion(codes[i].centre_x, codes[i].centre_y, latent.width,
                                            latent.height, direction),
                               true, codes[i].text, codes[i].format});
  if (out.decode_failed) flags.push_back("no-read");
  log["decoded"] = decoded;
  log["labels_in_view"] = out.sightings.size();
  log["times_ms"] = {{"convert", std::round(ms_between(t0, t1) * 100) / 100},
                     {"deblur", std::round(ms_between(t1, t2) * 100) / 100},
                     {"decode", std::round(ms_between(t2, t3) * 100) / 100}};
  if (!job.frame.truth.empty()) log["truth"] = job.frame.truth;
  log["flags"] = flags;
  out.processed = true;
  out.latent = std::move(latent);
  out.descriptor = imaging::to_descriptor(model.value());
  out.descriptor["capture"] = {{"sequence", job.frame.sequence},
                               {"timestamp_ns", job.frame.timestamp_ns},
                               {"exposure_counter", job.event.frame_counter}};
  if (!job.frame.truth.empty()) out.descriptor["capture"]["truth"] = job.frame.truth;
  if (!job.frame.truth_in_view.empty())
    out.descriptor["capture"]["truth_in_view"] = job.frame.truth_in_view;
  out.frame = std::move(job.frame);  // last: the lines above read it
  return out;
}

}  // namespace

void keep_freed_frame_memory() {
  mallopt(M_MMAP_THRESHOLD, 32 << 20);  // glibc's largest
  mallopt(M_TRIM_THRESHOLD, 512 << 20);
}

SessionOutcome run_session(SessionConfig config, const std::atomic<bool>& stop,
                           const SessionHooks& hooks) {
  keep_freed_frame_memory();
  SessionOutcome outcome;
  auto say = [&](const std::string& text) {
    if (hooks.message) hooks.message(text);
  };
  if (auto problem = check_config(config); !problem.empty()) {
    outcome.error = "config: " + problem;
    outcome.bad_input = true;
    return outcome;
  }
  // Light that varies across the field of view (calibrate flat): corrected per frame.
  std::optional<imaging::FlatField> flat;
  if (!config.optics.flat_field.empty()) {
    std::ifstream in(config.optics.flat_field);
    const auto json = nlohmann::json::parse(in, nullptr, false);
    auto parsed = json.is_discarded()
                      ? Result<imaging::FlatField, std::string>::failure("not readable JSON")
                      : imaging::flat_field_from_json(json);
    if (!parsed.ok()) {
      outcome.error =
          "config: optics.flat_field '" + config.optics.flat_field + "': " + parsed.error();
      outcome.bad_input = true;
      return outcome;
    }
    flat = std::move(parsed.value());
  }
  const bool sim_camera = config.camera.spec == "sim" || config.camera.spec.rfind("sim:", 0) == 0;
  if (sim_camera && config.controller.spec != "sim") {
    outcome.error = "camera 'sim' needs the virtual controller: set controller.spec = \"sim\"";
    outcome.bad_input = true;
    return outcome;
  }
  if (sim_camera && config.controller.sync != "slave") {
    outcome.error = "camera 'sim' strobes the controller: controller.sync must be \"slave\"";
    outcome.bad_input = true;
    return outcome;
  }

  // One virtual controller for the light probe and the session.
  SessionHooks line_hooks = hooks;
  if (config.controller.spec == "sim" && !line_hooks.virtual_controller)
    line_hooks.virtual_controller = std::make_shared<device::VirtualController>();

  // Scheme auto: the light measured on the line picks the scheme (light_probe.hpp).
  std::optional<SchemeLight> scheme_light;
  if (config.controller.code == "auto") {
    auto light = choose_scheme_from_light(config, line_hooks.virtual_controller,
                                          [&](const std::string& m) { say("light probe: " + m); });
    if (!light.ok()) {
      outcome.error = light.error().message;
      outcome.bad_input = light.error().bad_input;
      return outcome;
    }
    scheme_light = light.value();
    const codes::SchemeChoice& scheme = *config.controller.scheme;
    std::ostringstream text;
    text << "scheme auto: " << scheme.scheme << " at " << describe_scheme_light(*scheme_light)
         << "; regime map cell " << scheme.cell_electrons << " e-, read noise "
         << scheme.cell_read_noise << " e-, cap " << scheme.cell_cap << ": best coded scheme "
         << (scheme.margin_db >= 0 ? "+" : "") << scheme.margin_db
         << " dB against the best white strobe";
    say(text.str());
    if (const auto& l = scheme_light->level;
        l && l->paper_electrons < 1.25 * l->background_electrons)
      say("warning: scheme auto: the brightest paper is barely brighter than the rest of the "
          "probe frames: if no label was in view, the belt was taken for paper and the light "
          "is underestimated");
  }

  // Controller first: the camera may need it (sim), and it must be ready before frames.
  ControllerLink link;
  bool bad_input = false;
  if (auto problem = connect_controller(config, line_hooks, link, bad_input); !problem.empty()) {
    outcome.error = problem;
    outcome.bad_input = bad_input;
    return outcome;
  }

  auto camera =
      open_camera(config.camera, link.virtual_controller.get(), outcome.error, outcome.bad_input);
  if (!camera) return outcome;
  for (const auto& warning : camera->warnings()) say("warning: " + warning);
  const capture::FrameFormat format = camera->format();
  if (!capture::keeps_channels_apart(format.pixel_format))
    say("warning: pixel format " + capture::pixel_format_name(format.pixel_format) +
        " mixes the camera channels: the joint deblur loses accuracy (use raw Bayer or RGB)");

  // Faster FFT plans for the frame's rows, measured now: a worker that planned
  // on its first frame would stall the queue. Blurs up to kLongestPlannedBlurPx.
  imaging::Direction direction = imaging::Direction::kPlusX;
  imaging::parse_direction(config.optics.direction, direction);
  const bool along_x =
      direction == imaging::Direction::kPlusX || direction == imaging::Direction::kMinusX;
  imaging::measure_row_ffts(along_x ? format.width : format.height, kLongestPlannedBlurPx + 2);

  SessionFolder folder;
  const std::string folder_path = session_folder_name(config.output);
  if (auto p = folder.open(folder_path, config.output.disk_budget_mb); !p.empty()) {
    outcome.error = p;
    return outcome;
  }
  outcome.folder = folder_path;

  ResultsServer results;
  if (config.results.tcp_port >= 0) {
    if (auto p = results.listen(config.results.tcp_bind, config.results.tcp_port); !p.empty()) {
      outcome.error = p;
      return outcome;
    }
    if (hooks.listening) hooks.listening(results.port());
  }
  if (!config.results.serial.empty()) {
    if (auto p = results.open_serial(config.results.serial, config.results.serial_baud);
        !p.empty()) {
      outcome.error = p;
      return outcome;
    }
  }

  // Events from the controller's reader thread to the capture thread.
  std::mutex inbox_mutex;
  std::deque<ExposureRecord> inbox;
  std::atomic<std::uint64_t> events_received{0};
  std::atomic<std::uint64_t> events_missing{0};
  link.client->set_event_handler([&](const device::EventNotice& notice) {
    events_missing += notice.frames_missing_before;
    ++events_received;
    std::lock_guard lock(inbox_mutex);
    inbox.push_back(exposure_record(notice));
  });
  if (auto r = link.client->arm(); !r.ok()) {
    outcome.error = "controller: Arm: " + r.error().message;
    return outcome;
  }
  if (auto p = camera->start(); !p.empty()) {
    link.client->disarm();
    outcome.error = p;
    return outcome;
  }

  Shared shared(config);
  const std::int64_t start_ns = now_ns();

  // Workers. Without an encoder, the last confident blur estimate stands in for
  // frames without edges along the motion.
  std::atomic<double> last_blur_px{config.optics.nominal_blur_px};
  std::vector<std::thread> workers;
  for (int w = 0; w < config.processing.workers; ++w)
    workers.emplace_back([&] {
      FrameJob job;
      while (shared.jobs.pop(job)) {
        FrameOutcome o = process(job, config, last_blur_px, flat ? &*flat : nullptr);
        if (!o.processed) ++shared.processing_errors;
        shared.outcomes.push(std::move(o));
      }
    });

  // Per-frame model choices and guard flags, counted for the summary (results thread).
  std::map<std::string, std::uint64_t> model_counts, flag_counts;

  // Results thread: in capture order.
  ObjectTracker tracker(along_x ? format.width : format.height, config.processing.object_match_px);
  std::vector<ObjectResult> objects;
  std::vector<double> latencies;
  std::vector<double> processed_at_s;
  std::vector<Preview> previews;
  int previews_read = 0, previews_failed = 0;
  std::set<std::string> truth_seen;
  std::set<std::string> truth_in_view;
  std::uint64_t frames_saved = 0;
  std::uint64_t no_event_frames = 0;
  std::string save_error;
  std::thread results_thread([&] {
    std::map<std::uint64_t, FrameOutcome> waiting;
    std::uint64_t next = 0;
    std::int64_t last_progress = 0;
    auto publish = [&](std::vector<ObjectResult> finished) {
      for (auto& o : finished) {
        results.publish(result_line(o));
        objects.push_back(std::move(o));
      }
    };
    FrameOutcome o;
    while (shared.outcomes.pop(o)) {
      waiting.emplace(o.index, std::move(o));
      for (auto it = waiting.find(next); it != waiting.end(); it = waiting.find(next)) {
        FrameOutcome& f = it->second;
        if (f.log.contains("model")) ++model_counts[f.log["model"]["chosen"].get<std::string>()];
        if (f.log.contains("flags"))
          for (const auto& flag : f.log["flags"]) ++flag_counts[flag.get<std::string>()];
        if (f.processed) {
          const std::int64_t done = now_ns();
          f.latency_ms = ms_between(f.arrival_ns, done);
          f.log["latency_ms"] = std::round(f.latency_ms * 100) / 100;
          latencies.push_back(f.latency_ms);
          processed_at_s.push_back(ms_between(start_ns, done) * 1e-3);
          ++shared.frames_processed;
          tracker.observe(f.index, f.sequence, f.travel_px, f.sightings);
          publish(tracker.take_finished());
          for (const auto& t : f.truth) truth_seen.insert(t);
          for (const auto& t : f.truth_in_view) truth_in_view.insert(t);
          const bool keep = static_cast<int>(frames_saved) < config.output.keep_first_frames ||
                            (f.decode_failed && config.output.keep_failed_frames);
          // The report shows the first frames with a read label, and failures.
          const bool read_something = std::any_of(f.sightings.begin(), f.sightings.end(),
                                                  [](const Sighting& x) { return x.decoded; });
          const bool preview =
              (read_something && previews_read < 3) || (f.decode_failed && previews_failed < 3);
          // The frame's DN planes again (it converted without them), for these frames only.
          const auto dn = keep || preview ? capture::frame_to_dn(f.frame)
                                          : Result<imaging::Image, std::string>::success({});
          if (keep && !dn.ok()) {
            if (save_error.empty()) save_error = dn.error();
          } else if (keep) {
            if (auto p = folder.save_frame(f.sequence, dn.value(), f.descriptor, &f.latent);
                !p.empty()) {
              if (save_error.empty()) save_error = p;
            } else {
              ++frames_saved;
              f.log["files_saved"] = true;
            }
          }
          if (preview && dn.ok()) {
            Preview p = make_preview(f, dn.value());
            p.caption = "frame " + std::to_string(f.sequence) +
                        (f.decode_failed ? ": a label without a read" : ": labels read");
            previews.push_back(std::move(p));
            (f.decode_failed ? previews_failed : previews_read) += 1;
          }
        } else if (!f.log.contains("flags")) {
          f.log["flags"] = nlohmann::json::array({"error"});
        }
        folder.log(f.log);
        waiting.erase(it);
        ++next;
      }
      const std::int64_t now = now_ns();
      if (hooks.progress && now - last_progress > 500'000'000) {
        last_progress = now;
        Progress p;
        p.frames_captured = shared.frames_captured;
        p.frames_processed = shared.frames_processed;
        p.frames_dropped = shared.frames_dropped;
        p.objects = objects.size();
        p.objects_read = static_cast<std::uint64_t>(
            std::count_if(objects.begin(), objects.end(), [](const auto& x) { return x.read(); }));
        p.elapsed_s = ms_between(start_ns, now) * 1e-3;
        p.fps = p.elapsed_s > 0 ? static_cast<double>(p.frames_processed) / p.elapsed_s : 0;
        hooks.progress(p);
      }
    }
    publish(tracker.finish_all());
  });

  // Capture thread (this one): frames matched to events, dispatched or dropped.
  MatcherOptions matcher_options;
  matcher_options.tolerance_us = config.processing.match_tolerance_us;
  FrameMatcher matcher(matcher_options);
  std::map<std::uint64_t, capture::Frame> held;
  std::uint64_t next_index = 0;
  std::optional<ExposureRecord> previous_event;
  double travel = 0;
  std::uint64_t events_without_frame = 0;
  std::string stopped_by = "end of frames";
  std::string capture_error;

  auto drain_events = [&] {
    std::deque<ExposureRecord> got;
    {
      std::lock_guard lock(inbox_mutex);
      got.swap(inbox);
    }
    for (const auto& e : got) matcher.add_event(e);
  };
  auto log_orphans = [&] {
    for (const auto& orphan : matcher.take_orphan_events()) {
      ++events_without_frame;
      folder.log({{"event_without_frame",
                   {{"counter", orphan.event.frame_counter}, {"start_us", orphan.event.start_us}}},
                  {"why", orphan.why}});
    }
  };
  auto dispatch = [&](std::vector<FrameMatch> decided) {
    for (auto& m : decided) {
      auto frame_it = held.find(m.frame.sequence);
      if (frame_it == held.end()) continue;
      capture::Frame frame = std::move(frame_it->second);
      held.erase(frame_it);
      const std::uint64_t index = next_index++;
      if (!m.event) {
        ++no_event_frames;
        FrameOutcome o;
        o.index = index;
        o.sequence = frame.sequence;
        o.log = {{"index", index},
                 {"sequence", frame.sequence},
                 {"camera_ns", frame.timestamp_ns},
                 {"flags", {"no-event"}},
                 {"why", m.why}};
        shared.outcomes.push(std::move(o));
        continue;
      }
      const double speed = belt_speed_px_per_us(*m.event, config.optics);
      if (previous_event) {
        const double previous_speed = belt_speed_px_per_us(*previous_event, config.optics);
        travel += 0.5 * (speed + previous_speed) *
                  static_cast<double>(m.event->start_us - previous_event->start_us);
      }
      previous_event = m.event;
      FrameJob job;
      job.index = index;
      job.event = *m.event;
      job.residual_us = m.residual_us;
      job.travel_px = travel;
      job.match_note = m.why;
      const std::uint64_t sequence = frame.sequence;
      const std::int64_t camera_ns = frame.timestamp_ns;
      job.frame = std::move(frame);
      if (!shared.jobs.try_push(std::move(job))) {
        // The one place frames are dropped: processing is behind.
        ++shared.frames_dropped;
        FrameOutcome o;
        o.index = index;
        o.sequence = sequence;
        o.log = {{"index", index},
                 {"sequence", sequence},
                 {"camera_ns", camera_ns},
                 {"event", {{"counter", m.event->frame_counter}}},
                 {"flags", {"dropped"}},
                 {"why", "processing behind: the queue to the workers was full"}};
        shared.outcomes.push(std::move(o));
      }
    }
    log_orphans();
  };

  for (;;) {
    if (stop) {
      stopped_by = "stop request (SIGINT)";
      break;
    }
    if (config.processing.max_frames != 0 &&
        shared.frames_captured >= config.processing.max_frames) {
      stopped_by = "max_frames";
      break;
    }
    if (config.processing.max_seconds > 0 &&
        ms_between(start_ns, now_ns()) * 1e-3 >= config.processing.max_seconds) {
      stopped_by = "max_seconds";
      break;
    }
    capture::Frame frame;
    std::string frame_error;
    const auto got = camera->next_frame(frame, std::chrono::milliseconds(200), frame_error);
    if (got == capture::FrameWait::kEnd) break;
    if (got == capture::FrameWait::kError) {
      capture_error = frame_error;
      stopped_by = "camera error";
      break;
    }
    drain_events();
    if (got == capture::FrameWait::kTimeout) {
      dispatch(matcher.decide_waiting(now_ns()));  // late events may settle waiting frames
      continue;
    }
    ++shared.frames_captured;
    if (frame.host_arrival_ns == 0) frame.host_arrival_ns = now_ns();
    const FrameStamp stamp{frame.sequence, frame.timestamp_ns, frame.host_arrival_ns};
    held.emplace(frame.sequence, std::move(frame));
    dispatch(matcher.add_frame(stamp));
  }
  camera->stop();
  // Events still in flight from the controller: wait until none arrive for 100 ms (1 s at most).
  for (int i = 0; i < 10; ++i) {
    const std::uint64_t before = events_received;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    if (events_received == before) break;
  }
  drain_events();
  dispatch(matcher.flush());
  log_orphans();
  shared.jobs.close();
  for (auto& w : workers) w.join();
  shared.outcomes.close();
  results_thread.join();

  // LEDs off before anything else can fail.
  const auto disarmed = link.client->disarm();
  if (!disarmed.ok()) say("warning: controller Disarm failed: " + disarmed.error().message);
  const capture::CameraCounters counters = camera->counters();
  const double duration_s = ms_between(start_ns, now_ns()) * 1e-3;
  results.close();

  // Summary.
  nlohmann::json& s = outcome.summary;
  const auto read = static_cast<std::uint64_t>(
      std::count_if(objects.begin(), objects.end(), [](const auto& x) { return x.read(); }));
  double rate_sum = 0;
  for (const auto& o : objects) rate_sum += o.decode_rate();
  s["format"] = "flutterscan-session-summary";
  s["version"] = 1;
  s["camera"] = camera->name();
  s["controller"] = link.description;
  s["code"] = config.controller.code;
  if (const auto& scheme = config.controller.scheme)
    s["scheme_choice"] = {{"scheme", scheme->scheme},
                          {"expected_margin_db", scheme->margin_db},
                          {"regime_cell",
                           {{"electrons", scheme->cell_electrons},
                            {"read_noise_e", scheme->cell_read_noise},
                            {"cap", scheme->cell_cap}}}};
  if (scheme_light) s["scheme_choice"]["light"] = scheme_light_json(*scheme_light);
  s["method"] = imaging::method_name(config.processing.method);
  s["frame_size"] = std::to_string(format.width) + "x" + std::to_string(format.height) + " " +
                    capture::pixel_format_name(format.pixel_format);
  s["frames_captured"] = shared.frames_captured.load();
  s["frames_processed"] = shared.frames_processed.load();
  s["frames_dropped"] = shared.frames_dropped.load();
  s["frames_failed"] = shared.processing_errors.load();
  s["frames_without_event"] = no_event_frames;
  s["events_without_frame"] = events_without_frame;
  s["events_received"] = events_received.load();
  s["events_missing_by_counter"] = events_missing.load();
  s["camera_frames_lost"] = counters.frames_dropped;
  s["objects"] = objects.size();
  s["objects_read"] = read;
  s["object_read_rate"] = objects.empty() ? 0.0 : static_cast<double>(read) / objects.size();
  s["mean_decode_rate_per_object"] = objects.empty() ? 0.0 : rate_sum / objects.size();
  s["duration_s"] = std::round(duration_s * 1000) / 1000;
  s["fps"] = duration_s > 0 ? std::round(shared.frames_processed / duration_s * 10) / 10 : 0.0;
  s["latency_ms_p50"] = std::round(percentile(latencies, 50) * 10) / 10;
  s["latency_ms_p99"] = std::round(percentile(latencies, 99) * 10) / 10;
  s["clock_drift_ppm"] = std::round(matcher.clocks().drift_ppm() * 10) / 10;
  s["clock_fit_points"] = matcher.clocks().points;
  s["stopped_by"] = stopped_by;
  s["frames_saved"] = frames_saved;
  s["models_chosen"] = model_counts;
  s["frames_flagged"] = flag_counts;  // by flag: saturated, misfit, blur-disagrees, no-read, ...
  const RotationStats rotation = folder.rotation();
  s["rotation"] = {{"disk_budget_mb", config.output.disk_budget_mb},
                   {"frames_rotated", rotation.frames_rotated},
                   {"bytes_rotated", rotation.bytes_rotated},
                   {"frames_kept", rotation.frames_kept},
                   {"bytes_kept", rotation.bytes_kept}};
  if (rotation.frames_rotated > 0) {
    s["rotation"]["first_sequence_rotated"] = rotation.first_sequence_rotated;
    s["rotation"]["last_sequence_rotated"] = rotation.last_sequence_rotated;
  }
  s["results"] = {{"lines_sent", results.lines_sent()},
                  {"tcp_port", results.port()},
                  {"clients_dropped", results.clients_dropped()},
                  {"serial_lines_lost", results.serial_lines_lost()}};
  if (!truth_seen.empty()) {
    std::set<std::string> values;
    for (const auto& o : objects)
      if (o.read()) values.insert(o.value);
    nlohmann::json missed = nlohmann::json::array(), wrong = nlohmann::json::array();
    for (const auto& t : truth_seen)
      if (!values.count(t)) missed.push_back(t);
    for (const auto& v : values)
      if (!truth_in_view.count(v)) wrong.push_back(v);
    s["ground_truth"] = {{"labels_fully_in_view", truth_seen.size()},
                         {"labels_read", truth_seen.size() - missed.size()},
                         {"missed", missed},
                         {"wrong_values", wrong}};
  }
  nlohmann::json object_list = nlohmann::json::array();
  for (const auto& o : objects) object_list.push_back(nlohmann::json::parse(result_line(o)));
  s["object_results"] = object_list;
  if (!capture_error.empty()) s["error"] = capture_error;
  if (!save_error.empty()) s["save_error"] = save_error;

  folder.close();
  if (auto p = folder.write_file("summary.json", s.dump(2) + "\n"); !p.empty()) {
    outcome.error = p;
    return outcome;
  }
  if (config.output.report) {
    ReportInputs inputs;
    inputs.summary = s;
    inputs.objects = objects;
    inputs.previews = std::move(previews);
    inputs.latency_ms = latencies;
    if (!processed_at_s.empty()) {
      std::vector<double> per_second(static_cast<std::size_t>(processed_at_s.back()) + 1, 0.0);
      for (double t : processed_at_s) per_second[static_cast<std::size_t>(t)] += 1;
      if (per_second.size() > 1) per_second.pop_back();  // the last second is partial
      inputs.frames_per_second = per_second;
    }
    inputs.code = config.controller.parsed_code;
    if (auto p = write_report(folder_path, inputs); !p.empty()) {
      outcome.error = p;
      return outcome;
    }
  }
  if (!capture_error.empty()) outcome.error = capture_error;
  return outcome;
}

}  // namespace flutterscan::session
