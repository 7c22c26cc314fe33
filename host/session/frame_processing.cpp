#include "session/frame_processing.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "capture/frame_pixels.hpp"
#include "imaging/bayer.hpp"
#include "imaging/capture_descriptor.hpp"
#include "imaging/deblur.hpp"
#include "imaging/motion_frame.hpp"
#include "reader/barcode_reader.hpp"
#include "session/frame_model.hpp"
#include "session/model_fit.hpp"
#include "session/session_clock.hpp"

namespace flutterscan::session {

FrameOutcome process_frame(FrameJob& job, const SessionConfig& config,
                           std::atomic<double>& last_blur_px, const imaging::FlatField* flat) {
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
  // The simplest model that fits the frame, and the guards (model_fit.hpp), on
  // the frame turned once into the motion frame; raw Bayer frames keep the grey
  // global model on their raw planes (split in the mosaic's own geometry).
  const imaging::Direction direction = model.value().direction;
  imaging::Plane latent;         // the camera's orientation: decoded and kept
  imaging::Plane motion_latent;  // the motion frame: where labels are looked for
  std::string deblur_error;
  if (model.value().bayer_rggb) {
    auto r = imaging::deblur_bayer(electrons.channels[0], model.value(), options,
                                   imaging::BayerMode::kRawPlanes);
    if (r.ok()) {
      latent = std::move(r.value().latent);
      motion_latent = std::move(r.value().motion_latent);
    } else {
      deblur_error = r.error();
    }
  } else if (auto frame = imaging::MotionFrame::make(std::move(electrons), direction);
             !frame.ok()) {
    deblur_error = frame.error();
  } else {
    ModelFitConfig fit;
    fit.encoder = config.optics.encoder;
    fit.choose_latent = config.processing.choose_model;
    fit.line_time_us = config.optics.line_time_us;
    fit.slot_time_us = job.event.slot_time_us;
    fit.blur_check_every = config.processing.blur_check_every;
    fit.blur_tolerance = config.processing.blur_tolerance_pct / 100;
    fit.fallback_blur_px = last_blur_px.load();
    auto r = deblur_fitting_model(converted.value().saturated_share, frame.value(), model.value(),
                                  options, fit, job.index);
    if (r.ok()) {
      if (r.value().estimated_blur_px > 0) last_blur_px.store(r.value().estimated_blur_px);
      motion_latent = std::move(r.value().latent);
      latent = frame.value().to_camera(motion_latent);
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
  const std::vector<reader::LabelRegion> paper = reader::find_paper_runs(motion_latent);
  const bool labels_only = config.processing.decode_area == reader::DecodeArea::kLabels;
  const std::vector<reader::DecodeWindow> windows =
      labels_only ? reader::decode_windows(paper, latent.width, latent.height, direction)
                  : std::vector<reader::DecodeWindow>{};
  reader::BarcodeReadout readout;
  if (!labels_only || !windows.empty())
    readout = reader::read_barcodes(latent, config.processing.symbologies,
                                    config.processing.try_rotate, windows);
  if (labels_only) log["decode_windows"] = windows.size();
  const std::vector<reader::DecodedCode>& codes = readout.codes;
  if (!readout.decoder_fault.empty()) {
    // ZXing failed an internal assertion on this image: nothing read, the session goes on.
    log["decoder_fault"] = readout.decoder_fault;
    flags.push_back("decoder-fault");
  }
  std::vector<reader::LabelRegion> regions = paper;
  // A label cut by the frame is not judged; near the upstream edge the deblurred
  // image has no support: no judging there either.
  const double upstream = model.value().blur_px + 4;
  std::erase_if(regions, [&](const reader::LabelRegion& r) { return r.cut || r.begin < upstream; });
  const std::int64_t t3 = now_ns();

  std::vector<bool> used(codes.size(), false);
  nlohmann::json decoded = nlohmann::json::array();
  for (std::size_t i = 0; i < codes.size(); ++i)
    decoded.push_back({{"text", codes[i].text},
                       {"format", codes[i].format},
                       {"x", std::lround(codes[i].centre_x)},
                       {"y", std::lround(codes[i].centre_y)}});
  for (const reader::LabelRegion& r : regions) {
    bool any = false;
    for (std::size_t i = 0; i < codes.size(); ++i) {
      const double p = imaging::position_along_motion(
          direction, codes[i].centre_x, codes[i].centre_y, latent.width, latent.height);
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
      out.sightings.push_back(
          {imaging::position_along_motion(direction, codes[i].centre_x, codes[i].centre_y,
                                          latent.width, latent.height),
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

}  // namespace flutterscan::session
