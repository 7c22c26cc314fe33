#pragma once
// The summary stage (docs/session.md, "Session folder"): summary.json's
// figures, from what each stage counted, and report.html's inputs.

#include <nlohmann/json.hpp>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "capture/camera_source.hpp"
#include "session/capture_stage.hpp"
#include "session/frame_matcher.hpp"
#include "session/light_probe.hpp"
#include "session/matching_stage.hpp"
#include "session/pipeline.hpp"
#include "session/results_server.hpp"
#include "session/results_stage.hpp"
#include "session/session_config.hpp"
#include "session/session_folder.hpp"
#include "session/session_report.hpp"

namespace flutterscan::session {

/// \brief What the stages counted, as the summary reports it.
struct SessionCounts {
  std::string camera;                       ///< the camera's spec
  std::string controller;                   ///< the controller's description
  std::optional<SchemeLight> scheme_light;  ///< scheme auto: the light it was chosen at
  capture::FrameFormat format;
  // Capture and matching.
  std::uint64_t frames_captured = 0;
  std::uint64_t frames_processed = 0;
  std::uint64_t frames_dropped = 0;
  std::uint64_t frames_failed = 0;
  std::uint64_t frames_without_event = 0;
  std::uint64_t events_without_frame = 0;
  std::uint64_t events_received = 0;
  std::uint64_t events_missing_by_counter = 0;
  std::uint64_t camera_frames_lost = 0;
  double camera_making_ms = 0;  ///< host time the camera spent making its frames (the sim's)
  ClockRelation clocks;
  std::string stopped_by;
  std::string capture_error;
  double duration_s = 0;
  // Output.
  RotationStats rotation;
  std::uint64_t lines_sent = 0;
  int tcp_port = -1;
  std::uint64_t clients_dropped = 0;
  std::uint64_t serial_lines_lost = 0;
};

/// \brief What the stages counted once the session has ended: the frames of
/// `pipeline`, the matches and clocks of `matching`, the events of `inbox`,
/// the frames the camera lost (`camera`), why capture ended, the folder's
/// rotation and the lines of the result outputs (`server`). The line's names,
/// the scheme's light, the format and the duration are the caller's to fill in.
SessionCounts count_session(const Pipeline& pipeline, const MatchingStage& matching,
                            const EventInbox& inbox, const capture::CameraCounters& camera,
                            const CaptureEnd& capture_end, const SessionFolder& folder,
                            const ResultsServer& server);

/// \brief summary.json of a session under `config`.
nlohmann::json session_summary(const SessionConfig& config, const SessionCounts& counts,
                               const SessionResults& results);

/// \brief report.html's inputs: `summary`, and the objects, previews and timings
/// of `results` (moved out).
ReportInputs report_inputs(const nlohmann::json& summary, SessionResults& results,
                           const LedCode& code);

}  // namespace flutterscan::session
