#include "session/report_findings.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace flutterscan::session {

namespace {

std::uint64_t count(const nlohmann::json& j, const char* key) {
  const auto it = j.find(key);
  return it != j.end() && it->is_number_unsigned() ? it->get<std::uint64_t>() : 0;
}

std::uint64_t flagged(const nlohmann::json& summary, const char* flag) {
  const auto it = summary.find("frames_flagged");
  return it != summary.end() && it->is_object() ? count(*it, flag) : 0;
}

std::string percent(double share) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f%%", 100 * share);
  return text;
}

std::string frames(std::uint64_t n) {
  return std::to_string(n) + (n == 1 ? " frame" : " frames");
}

}  // namespace

const char* severity_name(Finding::Severity severity) {
  switch (severity) {
    case Finding::Severity::kProblem:
      return "problem";
    case Finding::Severity::kWarning:
      return "warning";
    case Finding::Severity::kNote:
      return "note";
    case Finding::Severity::kGood:
      return "good";
  }
  return "note";
}

std::vector<Finding> report_findings(const nlohmann::json& s) {
  using Severity = Finding::Severity;
  std::vector<Finding> out;
  auto add = [&](Severity severity, std::string what, std::string to_do) {
    out.push_back({severity, std::move(what), std::move(to_do)});
  };
  if (const auto error = s.value("error", std::string()); !error.empty())
    add(Severity::kProblem, "The session ended on an error: " + error + ".",
        "Fix what the error names (the camera or the controller named in it), then start again.");
  if (const auto error = s.value("save_error", std::string()); !error.empty())
    add(Severity::kProblem, "Frame files could not be saved: " + error + ".",
        "Check free space and write permission in the output folder (output.dir).");

  const std::uint64_t objects = count(s, "objects");
  const std::uint64_t read = count(s, "objects_read");
  const std::uint64_t captured = count(s, "frames_captured");
  if (objects == 0 && count(s, "frames_processed") > 0)
    add(Severity::kWarning, "No object passed the camera: no label was seen in any frame.",
        "Check that labels pass through the field of view and the belt moves (the encoder "
        "counts of each frame are in session.jsonl, event.encoder_delta).");
  if (objects > read) {
    const double rate = static_cast<double>(read) / static_cast<double>(objects);
    add(rate < 0.95 ? Severity::kProblem : Severity::kWarning,
        std::to_string(objects - read) + " of " + std::to_string(objects) +
            " objects were not read (NO-READ): read rate " + percent(rate) + ".",
        "Look at their frames (kept in frames/ with output.keep_failed_frames) for print "
        "quality, focus and light; `flutterscan replay FOLDER` tries them again with today's "
        "pipeline.");
  }
  if (const auto dropped = count(s, "frames_dropped"); dropped > 0)
    add(dropped * 100 > captured ? Severity::kProblem : Severity::kWarning,
        frames(dropped) + " of " + std::to_string(captured) +
            " captured were dropped: processing fell behind the camera.",
        "Lower the camera's frame rate, give the session more processing.workers if cores are "
        "free, or choose processing.method = \"joint-wiener\" (no second pass).");
  if (const auto failed = count(s, "frames_failed"); failed > 0) {
    const auto out_of_range = flagged(s, "blur-out-of-range");
    add(Severity::kProblem,
        frames(failed) + " failed to process" +
            (out_of_range > 0 ? " (" + std::to_string(out_of_range) + " with a blur out of range)"
                              : "") +
            ".",
        out_of_range > 0 ? "The encoder's travel per exposure gives a blur the code cannot "
                           "deblur: check optics.px_per_count (`flutterscan calibrate speed`) "
                           "and the exposure time."
                         : "The reason of each is in session.jsonl (the frame's `error`).");
  }
  if (const auto lost = std::max(count(s, "camera_frames_lost"), count(s, "events_without_frame"));
      lost > 0)
    add(Severity::kWarning,
        "The camera lost " + frames(lost) + ": the controller lit exposures that never arrived.",
        "Check the camera's link (cable, bandwidth, packet size) and that its frame rate is one "
        "it can deliver.");
  if (const auto without = count(s, "frames_without_event"); without > 0)
    add(Severity::kWarning,
        frames(without) + " arrived without an exposure event from the controller.",
        "Check the trigger wiring between the camera and the controller, and the controller's "
        "USB link (`flutterscan devices`).");
  if (const auto saturated = flagged(s, "saturated"); saturated > 0)
    add(Severity::kWarning, frames(saturated) + " saturated (too much light for the exposure).",
        "Lower the LEDs' current or the exposure time (`flutterscan calibrate light`).");
  const auto motion = flagged(s, "blur-off-encoder") + flagged(s, "motion-unfit") +
                      flagged(s, "blur-disagrees") + flagged(s, "misfit");
  if (motion > 0)
    add(Severity::kWarning,
        frames(motion) +
            " did not match the motion the encoder reported (flags blur-off-encoder, "
            "motion-unfit, blur-disagrees or misfit).",
        "Re-measure optics.px_per_count with `flutterscan calibrate speed`, check that the "
        "encoder is coupled to the belt without slip, and that the code in use is the "
        "controller's.");
  if (const auto budget = flagged(s, "second-pass-budget"); budget > 0)
    add(Severity::kNote,
        frames(budget) + " had label windows the cascade had no time to deblur again.",
        "If labels go unread at the same time, lower the frame rate or add cores.");
  if (const auto faults = flagged(s, "decoder-fault"); faults > 0)
    add(Severity::kNote, frames(faults) + " stopped the barcode decoder on an internal check.",
        "Nothing to do on the line; the frames are named in session.jsonl (decoder_fault).");
  if (const double drift = std::fabs(s.value("clock_drift_ppm", 0.0)); drift > 200)
    add(Severity::kNote,
        "The camera's and the controller's clocks drift " + std::to_string(std::lround(drift)) +
            " ppm apart (matching corrects it).",
        "");
  if (s.contains("rotation") && count(s["rotation"], "frames_rotated") > 0)
    add(Severity::kNote,
        std::to_string(count(s["rotation"], "frames_rotated")) +
            " kept frames' files were deleted to stay within the disk budget.",
        "Raise output.disk_budget_mb to keep more.");
  std::stable_sort(out.begin(), out.end(),
                   [](const Finding& a, const Finding& b) { return a.severity < b.severity; });
  if (out.empty())
    add(Severity::kGood,
        objects > 0 ? "Nothing went wrong: every object was read and no frame was lost."
                    : "Nothing went wrong: no frame was lost.",
        "");
  return out;
}

}  // namespace flutterscan::session
