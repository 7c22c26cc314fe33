#include "session/frame_processing.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "capture/frame_pixels.hpp"
#include "imaging/bayer.hpp"
#include "imaging/capture_descriptor.hpp"
#include "imaging/deblur.hpp"
#include "imaging/motion_frame.hpp"
#include "reader/barcode_reader.hpp"
#include "reader/code_reading.hpp"
#include "reader/code_regions.hpp"
#include "session/frame_model.hpp"
#include "session/model_fit.hpp"
#include "session/read_record.hpp"
#include "session/session_clock.hpp"

namespace flutterscan::session {
namespace {

// One frame's way through a worker, step by step (docs/session.md, "Workers"):
//   convert: event -> descriptor -> electrons
//   deblur:  flat field -> model fit + deblur (latent in the camera's orientation and the motion
//            frame)
//   decode:  paper runs, code regions -> decode
//   second pass (cascade): the windows read nothing in -> tv -> read again
//   record:  labels judged -> the frame's log line, descriptor and files

/// Why a step stopped the frame: the log's error and the flag it raises.
struct StepFailure {
  std::string error;
  std::string flag = "error";
};

/// The frame's identity in its outcome, and the head of its log line.
FrameOutcome start_outcome(const FrameJob& job) {
  FrameOutcome out;
  out.index = job.index;
  out.sequence = job.frame.sequence;
  out.travel_px = job.travel_px;
  out.arrival_ns = job.frame.host_arrival_ns;
  out.truth = job.frame.truth;
  out.truth_in_view = job.frame.truth_in_view;
  return out;
}

nlohmann::json log_head(const FrameJob& job, const SessionConfig& config) {
  nlohmann::json log = {{"index", job.index},
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
                        {"method", processing_method_name(config.processing)}};
  if (!job.match_note.empty()) log["match_note"] = job.match_note;
  return log;
}

/// The frame's model (from its exposure event) and its samples in electrons.
struct Converted {
  imaging::CaptureModel model;
  capture::ElectronFrame frame;
};

/// Step "convert": the descriptor from the event, the frame in electrons (one pass).
/// A blur the encoder implies but the frame cannot hold is flagged, not an error.
Result<Converted, StepFailure> convert(const FrameJob& job, const SessionConfig& config) {
  using Out = Result<Converted, StepFailure>;
  if (auto problem = blur_out_of_range(job.event, config.optics, job.frame.format);
      !problem.empty())
    return Out::failure({problem, "blur-out-of-range"});
  auto model = frame_model(job.event, config.controller.parsed_code, config, job.frame.format);
  if (!model.ok()) return Out::failure({model.error()});
  auto electrons = capture::frame_to_electrons(job.frame, model.value());
  if (!electrons.ok()) return Out::failure({electrons.error()});
  return Out::success(Converted{std::move(model.value()), std::move(electrons.value())});
}

/// The fused latent in the motion frame (where labels are looked for) and in
/// the camera's orientation (decoded and kept; for +x motion the same plane),
/// with the frame it came from and what the model fit said.
struct Deblurred {
  imaging::Plane motion_latent;
  std::optional<imaging::Plane> camera_latent;    ///< none: the motion latent is the camera's
  imaging::MotionFrame electrons;                 ///< empty for raw Bayer frames
  imaging::CaptureModel model;                    ///< the model the latent was deblurred with
  bool grey_global = false;                       ///< the latent is the grey global model's
  bool per_channel = false;                       ///< the latent is the per-channel model's
  std::vector<std::string> flags;                 ///< guards that fired
  nlohmann::json log = nlohmann::json::object();  ///< model fit: {"model": ..., "guards": ...}

  const imaging::Plane& latent() const { return camera_latent ? *camera_latent : motion_latent; }
  imaging::Plane take_latent() {
    return camera_latent ? std::move(*camera_latent) : std::move(motion_latent);
  }
};

/// Raw Bayer frames: the grey global model on their raw planes (split in the
/// mosaic's own geometry), no flat field.
Result<Deblurred, StepFailure> deblur_bayer_frame(const Converted& in,
                                                  const imaging::DeblurOptions& options) {
  using Out = Result<Deblurred, StepFailure>;
  auto r = imaging::deblur_bayer(in.frame.electrons.channels[0], in.model, options,
                                 imaging::BayerMode::kRawPlanes);
  if (!r.ok()) return Out::failure({r.error()});
  Deblurred out;
  out.camera_latent = std::move(r.value().latent);
  out.motion_latent = std::move(r.value().motion_latent);
  out.model = in.model;
  return Out::success(std::move(out));
}

/// Step "deblur": the flat field (if any), then the simplest model that fits
/// and the guards (model_fit.hpp) on the frame turned once into the motion
/// frame, which the result keeps (for the second pass).
Result<Deblurred, StepFailure> deblur(Converted& in, const FrameJob& job,
                                      const SessionConfig& config, WorkerShared& shared,
                                      const imaging::FlatField* flat) {
  using Out = Result<Deblurred, StepFailure>;
  const imaging::DeblurOptions options = deblur_options(config.processing);
  if (in.model.bayer_rggb) return deblur_bayer_frame(in, options);
  if (flat != nullptr)
    if (auto problem = imaging::apply_flat_field(in.frame.electrons, *flat); !problem.empty())
      return Out::failure({"optics.flat_field: " + problem});
  // The conversion's bound on the values holds until a flat field rescales them.
  const imaging::PixelValues values =
      flat != nullptr ? imaging::PixelValues::kScan : in.frame.values;
  // The conversion's row levels hold until a flat field rescales the rows.
  auto frame = imaging::MotionFrame::make(
      std::move(in.frame.electrons), in.model.direction, values,
      flat != nullptr ? imaging::RowLevels{} : std::move(in.frame.levels));
  if (!frame.ok()) return Out::failure({frame.error()});
  ModelFitConfig fit;
  fit.encoder = config.optics.encoder;
  fit.choose_latent = config.processing.choose_model;
  fit.line_time_us = config.optics.line_time_us;
  fit.slot_time_us = job.event.slot_time_us;
  fit.blur_check_every = config.processing.blur_check_every;
  fit.blur_tolerance = config.processing.blur_tolerance_pct / 100;
  fit.fallback_blur_px = shared.last_blur_px.load();
  if (!config.processing.refine_when_behind &&
      behind_queue(job.waiting_behind, config.processing.queue_depth)) {
    const double ratio = shared.motion_ratio.load();
    fit.reuse_motion_ratio = ratio > 0 ? ratio : 1.0;
  }
  auto r = deblur_fitting_model(in.frame.saturated_share, frame.value(), in.model, options, fit,
                                job.index);
  if (!r.ok()) return Out::failure({r.error()});
  if (r.value().estimated_blur_px > 0) shared.last_blur_px.store(r.value().estimated_blur_px);
  if (r.value().refinement_used && in.model.blur_px > 0)
    shared.motion_ratio.store(r.value().model.blur_px / in.model.blur_px);
  Deblurred out;
  out.motion_latent = std::move(r.value().latent);
  if (in.model.direction != imaging::Direction::kPlusX)
    out.camera_latent = frame.value().to_camera(out.motion_latent);
  out.electrons = std::move(frame.value());
  out.model = std::move(r.value().model);
  out.grey_global = r.value().grey_global;
  out.per_channel = r.value().per_channel;
  out.flags = std::move(r.value().flags);
  out.log = std::move(r.value().log);
  return Out::success(std::move(out));
}

/// What the decode found on one frame.
struct Decoded {
  std::vector<reader::LabelRegion> paper;  ///< paper runs along the motion (motion frame)
  std::vector<reader::LabelRegion> code;   ///< where the latent looks like a code (motion frame)
  reader::BarcodeReadout readout;
  std::optional<std::size_t> windows;  ///< decode_area "labels": the windows read
  double budget_ms = 0;                ///< the decode's time (0: every window)
  /// Paper runs and code regions whose windows the decode's budget left: not
  /// judged and not deblurred again in this frame; read first in a frame after.
  std::vector<reader::LabelRegion> left;

  bool was_left(const reader::LabelRegion& r) const {
    return std::any_of(left.begin(), left.end(), [&](const reader::LabelRegion& l) {
      return l.begin == r.begin && l.end == r.end && l.across_begin == r.across_begin &&
             l.across_end == r.across_end;
    });
  }
};

/// When frame `job`'s result is due (session clock, ns; 0: never): processing.latency_ms
/// after it arrived; "auto": workers + 1 frame periods (a worker takes a frame every `workers`
/// periods: one that waited up to a period for its worker and then took the worker's whole
/// round is done by then; later, the worker is late for its next), never while the period is
/// unknown or where frames do not arrive as they are exposed (WorkerShared::live_arrivals).
std::int64_t frame_deadline_ns(const FrameJob& job, const ProcessingConfig& processing,
                               const WorkerShared& shared) {
  double ms = processing.latency_ms;
  if (ms < 0 && !shared.live_arrivals) return 0;
  if (ms < 0) ms = (processing.workers + 1) * shared.second_pass.period_ms();
  if (ms <= 0 || ms >= kMaxLatencyMs || job.frame.host_arrival_ns <= 0) return 0;
  return job.frame.host_arrival_ns + static_cast<std::int64_t>(ms * 1e6);
}

/// The first pass's decode time for a frame that has taken `spent_ms` so far
/// (its conversion, deblur and regions) and is due in `due_ms` (< 0: never) (processing.decode_ms;
/// "auto": the frame's share of the workers' time less that, and no more than `due_ms`; at least
/// 1 ms: the first window, where the deadline holds it; the frame rate unknown, no limit).
double decode_budget_ms(const ProcessingConfig& processing, const WorkerShared& shared,
                        double spent_ms, double due_ms) {
  if (processing.decode_ms >= 0) return processing.decode_ms;
  const double share = shared.second_pass.frame_share_ms();
  if (share <= 0) return 0;
  double ms = share - spent_ms;
  if (due_ms >= 0) ms = std::min(ms, due_ms);
  return std::max(1.0, ms);
}

/// Keeps what a window's first view costs a megapixel lately (a moving mean
/// over frames, a fifth the newest's): the decode cuts regions to what its
/// budget reads in one view by it. Frames whose views saw less than a tenth of
/// a megapixel are not weighed (their time is mostly fixed costs).
void note_decode_rate(const reader::BarcodeReadout& readout, WorkerShared& shared) {
  if (readout.first_view_px < 100000) return;
  const double rate = readout.first_view_ms / (static_cast<double>(readout.first_view_px) / 1e6);
  const double before = shared.decode_ms_per_mpx.load();
  shared.decode_ms_per_mpx.store(before > 0 ? 0.8 * before + 0.2 * rate : rate);
}

/// Where region `r` (motion frame) of a frame at belt travel `travel_px` lies on the belt.
BeltBox on_belt(const reader::LabelRegion& r, double travel_px) {
  return {r.begin - travel_px, r.end - travel_px, static_cast<double>(r.across_begin),
          static_cast<double>(r.across_end)};
}

/// Step "decode": the paper and the code regions along the motion, then the
/// codes in processing.decode_area (the paper runs and the code regions off
/// them, widened; or the whole frame) with the session's reader options,
/// within what is left of the frame's share since `frame_start_ns`.
Decoded decode(const Deblurred& image, imaging::Direction direction,
               const ProcessingConfig& processing, const FrameJob& job, WorkerShared& shared,
               std::int64_t frame_start_ns, std::int64_t deadline_ns) {
  Decoded out;
  out.paper = reader::find_paper_runs(image.motion_latent);
  // Code regions serve only the labels area and the cascade's second pass.
  if (processing.decode_area == reader::DecodeArea::kLabels || processing.cascade)
    out.code = reader::find_code_regions(image.motion_latent);
  // The cascade's second pass reads the windows this pass read nothing in with
  // zbar (under the frame's budget); without it, this pass is the only one.
  reader::ReaderOptions options = reader_options(processing);
  options.second_decoder = !processing.cascade;
  // Area "frame" reads the whole frame as one window: no regions, no budget.
  // A region larger than one view of the budget is read as tiles of that size.
  std::vector<reader::LabelRegion> regions_whole;
  std::vector<reader::RegionTile> tiles;
  if (processing.decode_area == reader::DecodeArea::kLabels) {
    regions_whole = reader::regions_to_read(out.paper, out.code);
    const std::int64_t now = now_ns();
    options.budget.deadline_ms = deadline_ns > 0 ? std::max(0.0, ms_between(now, deadline_ns)) : -1;
    options.budget.ms = decode_budget_ms(processing, shared, ms_between(frame_start_ns, now),
                                         options.budget.deadline_ms);
    options.budget.view_ms_per_mpx = shared.decode_ms_per_mpx.load();
    const auto tile_px =
        options.budget.ms > 0 && options.budget.view_ms_per_mpx > 0
            ? static_cast<long long>(options.budget.ms / options.budget.view_ms_per_mpx * 1e6)
            : 0LL;
    tiles = reader::cut_to_tiles(regions_whole, image.motion_latent.height, tile_px);
  }
  // Within a budget, the tiles no frame tried lately first (what one frame leaves,
  // the next reads: a label passes through several), each group the most like
  // a linear code first.
  if (options.budget.ms > 0) {
    std::vector<reader::LabelRegion> tile_regions;
    for (const reader::RegionTile& t : tiles) tile_regions.push_back(t.tile);
    const std::vector<double> likeness = reader::bar_likeness(image.motion_latent, tile_regions);
    std::vector<std::tuple<bool, double, reader::RegionTile>> ranked;
    for (std::size_t i = 0; i < tiles.size(); ++i)
      ranked.emplace_back(shared.belt_tried.any_over(on_belt(tiles[i].tile, job.travel_px)),
                          -likeness[i], tiles[i]);
    std::stable_sort(ranked.begin(), ranked.end(), [](const auto& a, const auto& b) {
      return std::tie(std::get<0>(a), std::get<1>(a)) < std::tie(std::get<0>(b), std::get<1>(b));
    });
    for (std::size_t i = 0; i < tiles.size(); ++i) tiles[i] = std::get<2>(ranked[i]);
  }
  std::vector<reader::LabelRegion> regions;
  for (const reader::RegionTile& t : tiles) regions.push_back(t.tile);
  reader::CodeReading reading = reader::read_codes(image.latent(), regions, direction, options);
  note_decode_rate(reading.readout, shared);
  // A window started counts as tried (the next frame starts with another); one
  // not started or cut short with nothing read leaves its region: not judged here.
  const std::vector<std::size_t>& unstarted = reading.readout.windows_left;
  const std::vector<std::size_t>& cut = reading.readout.windows_cut;
  std::vector<bool> left(regions_whole.size(), false);
  for (std::size_t i = 0; i < tiles.size(); ++i) {
    const bool started = std::find(unstarted.begin(), unstarted.end(), i) == unstarted.end();
    if (started) shared.belt_tried.add(on_belt(tiles[i].tile, job.travel_px));
    if (!started || std::find(cut.begin(), cut.end(), i) != cut.end()) left[tiles[i].region] = true;
  }
  for (std::size_t r = 0; r < regions_whole.size(); ++r)
    if (left[r]) out.left.push_back(regions_whole[r]);
  out.readout = std::move(reading.readout);
  out.windows = reading.windows;
  out.budget_ms = options.budget.ms;
  return out;
}

/// The columns from the upstream edge where the deblurred image has no
/// support: the blur plus 4 px (rounded up: a region starting at a column
/// below it starts within blur_px + 4).
int unsupported_columns(double blur_px) {
  return static_cast<int>(std::ceil(blur_px)) + 4;
}

/// Labels judged: each whole label region in view (not cut by the frame, not
/// within unsupported_columns of the upstream edge) is a sighting, read when a
/// code lies on it (8 px slack), else NO-READ; codes off the judged regions are
/// sightings of their own.
std::vector<reader::LabelRegion> judged_regions(const Decoded& decoded, double blur_px) {
  std::vector<reader::LabelRegion> regions = decoded.paper;
  const int upstream = unsupported_columns(blur_px);
  std::erase_if(regions, [&](const reader::LabelRegion& r) {
    return r.cut || r.begin < upstream || decoded.was_left(r);
  });
  return regions;
}

/// The code regions in view: their part beyond unsupported_columns (where the
/// latent often looks busy), at least two cells wide there; not those cut by
/// the downstream edge, nor those coming into view: a code region reaching into
/// the unsupported columns on paper that reaches into them too is a label's code
/// still partly upstream of the view, whole in a later frame (counted in `entering`).
std::vector<reader::LabelRegion> code_in_view(const Decoded& decoded, double blur_px, int length,
                                              int& entering) {
  constexpr int kMinWidth = 32;
  const int upstream = unsupported_columns(blur_px);
  std::vector<reader::LabelRegion> regions;
  entering = 0;
  for (reader::LabelRegion r : decoded.code) {
    if (decoded.was_left(r)) continue;
    const bool on_entering_label =
        r.begin < upstream &&
        std::any_of(decoded.paper.begin(), decoded.paper.end(), [&](const reader::LabelRegion& p) {
          return p.begin < upstream && p.overlaps(r);
        });
    r.begin = std::max(r.begin, upstream);
    if (r.end >= length || r.end - r.begin < kMinWidth) continue;
    if (on_entering_label) {
      ++entering;
      continue;
    }
    regions.push_back(r);
  }
  return regions;
}

void judge_labels(const Decoded& decoded, const imaging::Plane& latent,
                  imaging::Direction direction, double blur_px, FrameOutcome& out) {
  const std::vector<reader::LabelRegion> regions = judged_regions(decoded, blur_px);
  const std::vector<reader::DecodedCode>& codes = decoded.readout.codes;
  auto position = [&](const reader::DecodedCode& code) {
    return imaging::position_along_motion(direction, code.centre_x, code.centre_y, latent.width,
                                          latent.height);
  };
  auto read = [&](const reader::DecodedCode& code) {
    Sighting s;
    s.position_px = position(code);
    s.across_px = imaging::moves_along_x(direction) ? code.centre_y : code.centre_x;
    s.decoded = true;
    s.value = code.text;
    s.format = code.format;
    s.code = code;
    return s;
  };
  std::vector<bool> used(codes.size(), false);
  for (const reader::LabelRegion& r : regions) {
    bool any = false;
    for (std::size_t i = 0; i < codes.size(); ++i) {
      const double p = position(codes[i]);
      if (p >= r.begin - 8 && p <= r.end + 8 && !used[i]) {
        used[i] = true;
        any = true;
        out.sightings.push_back(read(codes[i]));
      }
    }
    if (!any) {
      Sighting s;
      s.position_px = 0.5 * (r.begin + r.end);
      s.across_px = r.rows_measured()
                        ? 0.5 * (r.across_begin + r.across_end)
                        : 0.5 * (imaging::moves_along_x(direction) ? latent.height : latent.width);
      out.sightings.push_back(std::move(s));
      out.decode_failed = true;
    }
  }
  for (std::size_t i = 0; i < codes.size(); ++i)
    if (!used[i]) out.sightings.push_back(read(codes[i]));
}

/// Every read against the label of its value the simulator placed (sim frames).
std::vector<ReadTruthCheck> check_reads(const std::vector<reader::DecodedCode>& codes,
                                        const std::vector<capture::TruthLabel>& truth) {
  std::vector<ReadTruthCheck> checks;
  if (truth.empty()) return checks;
  for (const reader::DecodedCode& code : codes) {
    ReadTruthCheck check;
    check.value = code.text;
    const auto label = std::find_if(truth.begin(), truth.end(), [&](const capture::TruthLabel& t) {
      return t.value == code.text;
    });
    if (label != truth.end()) {
      check.found = true;
      for (int i = 0; i < 4; ++i)
        check.corner_error_px = std::max(
            {check.corner_error_px, std::abs(code.quality.corners[i].x - label->corners[i][0]),
             std::abs(code.quality.corners[i].y - label->corners[i][1])});
      check.module_error = std::abs(code.quality.module_px - label->module_px) / label->module_px;
      check.symbology_id_matches = code.symbology_id == label->symbology_id;
    }
    checks.push_back(std::move(check));
  }
  return checks;
}

/// Each code read: its text, format and centre in the frame, its code record
/// (read_record.hpp) and its centre on the belt (u, across).
nlohmann::json decoded_json(const std::vector<reader::DecodedCode>& codes,
                            imaging::Direction direction, const imaging::Plane& latent,
                            double travel_px) {
  nlohmann::json decoded = nlohmann::json::array();
  for (const reader::DecodedCode& code : codes) {
    nlohmann::json entry = value_json(code);
    entry["x"] = std::lround(code.centre_x);
    entry["y"] = std::lround(code.centre_y);
    entry["view"] = reader::luminance_view_name(code.luminance);
    entry.update(code_record(code));
    const double along = imaging::position_along_motion(direction, code.centre_x, code.centre_y,
                                                        latent.width, latent.height);
    const double across = imaging::moves_along_x(direction) ? code.centre_y : code.centre_x;
    entry["centre_belt_px"] = {rounded(along - travel_px, 1), rounded(across, 1)};
    decoded.push_back(std::move(entry));
  }
  return decoded;
}

/// The frame part of every sighting's record: trigger, blur, decode time.
void stamp_sightings(const FrameJob& job, const nlohmann::json& log, double blur_px,
                     double decode_ms, FrameOutcome& out) {
  SightingFrame frame;
  frame.sequence = job.frame.sequence;
  frame.camera_ns = job.frame.timestamp_ns;
  frame.exposure_counter = job.event.frame_counter;
  frame.encoder_delta = job.event.encoder_delta;
  frame.travel_px = job.travel_px;
  frame.blur_px = blur_px;
  if (const auto motion = log.find("motion"); motion != log.end() && motion->is_object()) {
    if (motion->contains("encoder_blur_px"))
      frame.encoder_blur_px = (*motion)["encoder_blur_px"].get<double>();
    if (motion->contains("refined_blur_px"))
      frame.refined_blur_px = (*motion)["refined_blur_px"].get<double>();
  }
  frame.decode_ms = decode_ms;
  for (Sighting& s : out.sightings) s.frame = frame;
}

double rounded_ms(std::int64_t from_ns, std::int64_t to_ns) {
  return std::round(ms_between(from_ns, to_ns) * 100) / 100;
}

/// Step "record": the frame's log line, its descriptor, and the frame and its
/// latent moved into the outcome (kept for its files and previews).
void record(FrameJob& job, const imaging::CaptureModel& model, imaging::Plane latent,
            FrameOutcome& out) {
  out.processed = true;
  out.latent = std::move(latent);
  out.descriptor = imaging::to_descriptor(model);
  out.descriptor["capture"] = {{"sequence", job.frame.sequence},
                               {"timestamp_ns", job.frame.timestamp_ns},
                               {"exposure_counter", job.event.frame_counter}};
  if (!job.frame.truth.empty()) out.descriptor["capture"]["truth"] = job.frame.truth;
  if (!job.frame.truth_in_view.empty())
    out.descriptor["capture"]["truth_in_view"] = job.frame.truth_in_view;
  out.frame = std::move(job.frame);  // last: the lines above read it
}

/// `out` for a frame a step stopped: the error and its flag after `flags`.
FrameOutcome stopped(FrameOutcome out, const StepFailure& failure, nlohmann::json flags) {
  out.log["error"] = failure.error;
  flags.push_back(failure.flag);
  out.log["flags"] = flags;
  return out;
}

/// Step "second pass" (method "cascade"): the code regions and the judged
/// label windows in view the decode read nothing in (retry_regions), deblurred
/// again by tv and read again, within the budget; the codes found join `decoded`, its log line and
/// flag join `out`.
void second_pass(Deblurred& image, Decoded& decoded, const FrameJob& job,
                 const ProcessingConfig& processing, double first_pass_ms, std::int64_t deadline_ns,
                 WorkerShared& shared, FrameOutcome& out, nlohmann::json& flags) {
  const imaging::Plane& latent = image.latent();
  const imaging::Direction direction = image.model.direction;
  for (const reader::DecodedCode& code : decoded.readout.codes)
    shared.belt_reads.add(belt_box(code, direction, latent.width, latent.height, job.travel_px));
  shared.second_pass.add_frame(job.index, job.frame.timestamp_ns, first_pass_ms);
  if (!image.grey_global && !image.per_channel) {
    out.log["second_pass"] = {{"not_run", image.electrons.channel_count() == 0
                                              ? "a raw Bayer frame"
                                              : "the code's phase differs row by row"}};
    return;
  }
  int entering = 0;
  const std::vector<reader::LabelRegion> unread = retry_regions(
      unread_runs(judged_regions(decoded, image.model.blur_px), decoded.readout, direction,
                  latent.width, latent.height),
      unread_runs(code_in_view(decoded, image.model.blur_px, image.motion_latent.width, entering),
                  decoded.readout, direction, latent.width, latent.height));
  if (entering > 0) out.log["second_pass"]["entering"] = entering;
  if (unread.empty()) return;
  const SecondPassFrame frame{
      image.electrons,     image.model,
      image.motion_latent, image.camera_latent ? &*image.camera_latent : nullptr,
      job.travel_px,       deadline_ns};
  const SecondPass pass =
      run_second_pass(frame, unread, reader_options(processing), processing.second_pass_tries,
                      shared.second_pass, shared.belt_reads, decoded.readout);
  out.log["second_pass"].update(pass.log(shared.second_pass.credit_ms()));
  if (pass.skipped > 0) flags.push_back("second-pass-budget");
  if (pass.past_deadline > 0) flags.push_back("deadline");
}

}  // namespace

bool behind_queue(std::size_t waiting, std::size_t queue_depth) {
  return waiting > 0 && waiting >= (queue_depth + 1) / 2;
}

imaging::DeblurOptions deblur_options(const ProcessingConfig& processing) {
  imaging::DeblurOptions options;
  options.method = processing.method;
  options.threads = processing.threads_per_worker;
  options.plan_effort = imaging::PlanEffort::kMeasuredIfKnown;    // measured before streaming
  options.skip_flat_rows = true;                                  // the belt between labels
  options.tv_weight_per_noise = imaging::kReadingWeightPerNoise;  // tv: deblurred to be read
  return options;
}

FrameOutcome process_frame(FrameJob& job, const SessionConfig& config, WorkerShared& shared,
                           const imaging::FlatField* flat) {
  FrameOutcome out = start_outcome(job);
  const std::int64_t t0 = now_ns();
  const std::int64_t deadline_ns = frame_deadline_ns(job, config.processing, shared);
  out.log = log_head(job, config);
  nlohmann::json flags = nlohmann::json::array();

  auto converted = convert(job, config);
  if (!converted.ok()) return stopped(std::move(out), converted.error(), flags);
  out.log["blur_px"] = std::round(converted.value().model.blur_px * 100) / 100;
  const std::int64_t t1 = now_ns();

  auto deblurred = deblur(converted.value(), job, config, shared, flat);
  const std::int64_t t2 = now_ns();
  if (!deblurred.ok()) return stopped(std::move(out), deblurred.error(), flags);
  for (const auto& flag : deblurred.value().flags) flags.push_back(flag);
  out.log.update(deblurred.value().log);

  const imaging::CaptureModel& model = deblurred.value().model;
  Decoded decoded =
      decode(deblurred.value(), model.direction, config.processing, job, shared, t0, deadline_ns);
  if (decoded.windows) out.log["decode_windows"] = *decoded.windows;
  if (decoded.budget_ms > 0 && decoded.budget_ms < kMaxDecodeMs)
    out.log["decode_budget_ms"] = std::round(decoded.budget_ms * 10) / 10;
  if (!decoded.left.empty()) {
    // Over the decode's budget: counted and flagged, read in a frame after.
    out.log["decode_left"] = decoded.left.size();
    flags.push_back("decode-budget");
  }
  if (!decoded.readout.decoder_fault.empty()) {
    // ZXing failed an internal assertion on this image: nothing read, the session goes on.
    out.log["decoder_fault"] = decoded.readout.decoder_fault;
    flags.push_back("decoder-fault");
  }
  const std::int64_t t3 = now_ns();
  if (config.processing.cascade && decoded.readout.decoder_fault.empty())
    second_pass(deblurred.value(), decoded, job, config.processing, ms_between(t0, t3), deadline_ns,
                shared, out, flags);
  const std::int64_t t4 = now_ns();

  const imaging::Plane& latent = deblurred.value().latent();
  judge_labels(decoded, latent, model.direction, model.blur_px, out);
  stamp_sightings(job, out.log, model.blur_px, ms_between(t2, t4), out);
  if (out.decode_failed) flags.push_back("no-read");
  out.log["decoded"] = decoded_json(decoded.readout.codes, model.direction, latent, job.travel_px);
  if (!decoded.readout.unconfirmed.empty()) {
    nlohmann::json unconfirmed = nlohmann::json::array();
    for (const reader::DecodedCode& code : decoded.readout.unconfirmed) {
      nlohmann::json value = value_json(code);
      value["x"] = std::lround(code.centre_x);
      value["y"] = std::lround(code.centre_y);
      unconfirmed.push_back(std::move(value));
    }
    out.log["unconfirmed"] = std::move(unconfirmed);
  }
  out.log["labels_in_view"] = out.sightings.size();
  out.log["times_ms"] = {{"convert", rounded_ms(t0, t1)},
                         {"deblur", rounded_ms(t1, t2)},
                         {"decode", rounded_ms(t2, t3)}};
  if (config.processing.cascade) out.log["times_ms"]["second_pass"] = rounded_ms(t3, t4);
  if (!job.frame.truth.empty()) out.log["truth"] = job.frame.truth;
  out.truth_checks = check_reads(decoded.readout.codes, job.frame.truth_labels);
  if (!out.truth_checks.empty()) {
    nlohmann::json checks = nlohmann::json::array();
    for (const ReadTruthCheck& c : out.truth_checks)
      checks.push_back({{"value", c.value},
                        {"found", c.found},
                        {"corner_error_px", rounded(c.corner_error_px, 2)},
                        {"module_error_pct", rounded(100 * c.module_error, 1)},
                        {"symbology_id_matches", c.symbology_id_matches}});
    out.log["truth_check"] = checks;
  }
  out.log["flags"] = flags;
  record(job, model, deblurred.value().take_latent(), out);
  return out;
}

}  // namespace flutterscan::session
