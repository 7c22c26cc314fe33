#pragma once
// The results stage (docs/session.md, "Objects and results"): one thread takes
// the frames' outcomes as the workers finish them and handles them in capture
// order: the frame's latency, its sightings tracked as objects on the belt
// (each finished object published as one result line), its session.jsonl
// line, its files (the first frames, and failures) and its report preview;
// counts of models chosen and flags for the summary; a progress line about
// twice a second; the live view's snapshot, when there is one (live_view.hpp).

#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "session/frame_saver.hpp"
#include "session/object_tracker.hpp"
#include "session/pipeline.hpp"
#include "session/rate_timeline.hpp"
#include "session/results_server.hpp"
#include "session/session.hpp"
#include "session/session_config.hpp"
#include "session/session_folder.hpp"
#include "session/session_report.hpp"
#include "session/value_distribution.hpp"

namespace flutterscan::session {

class MqttPublisher;
class LiveView;

/// \brief The read record against the simulator's truth (sim sessions): how
/// many reads had their label found, and how many of those were within the
/// targets (corners within 2 px, module size within 10%, identifier equal).
struct ReadRecordTruth {
  std::uint64_t reads_checked = 0;  ///< reads of a label whole in the frame
  std::uint64_t reads_without_label = 0;
  std::uint64_t corners_within_2px = 0;
  std::uint64_t modules_within_10pct = 0;
  std::uint64_t symbology_ids_matching = 0;
  double worst_corner_error_px = 0;
  double worst_module_error = 0;
};

/// \brief The cascade's second passes over the session (processing.method "cascade").
struct SecondPassTally {
  std::uint64_t frames = 0;           ///< frames with a window deblurred again
  std::uint64_t windows = 0;          ///< windows deblurred again
  std::uint64_t windows_read = 0;     ///< of which read something
  std::uint64_t codes_read = 0;       ///< codes they read
  std::uint64_t windows_skipped = 0;  ///< left as they were: the budget was spent
  std::uint64_t frames_skipping = 0;  ///< frames with such a window (flag second-pass-budget)
  ValueDistribution window_ms;        ///< each window's deblur and decode
  /// The first few values they read (at most kSecondPassValuesKept, in order).
  std::vector<std::string> values;
};
inline constexpr std::size_t kSecondPassValuesKept = 20;

/// \brief The objects of the session: every one counted; the records of the
/// latest kept for the summary and the report (every record is in session.jsonl).
struct ObjectTally {
  std::uint64_t objects = 0;
  std::uint64_t read = 0;
  double decode_rate_sum = 0;         ///< of every object: decoded frames / frames seen
  std::deque<ObjectResult> latest;    ///< the last kObjectsListed, in the order published
  std::set<std::string> values_read;  ///< sim sessions (with truth) only: every value read

  /// \brief Counts `object` and keeps it among the latest; `with_truth`: its value too.
  void add(ObjectResult object, bool with_truth);
};
inline constexpr std::size_t kObjectsListed = 500;

/// \brief What the results stage gathered for the summary and the report; its
/// memory stays bounded however long the session runs (but for the sim's truth sets).
struct SessionResults {
  ObjectTally objects;
  ValueDistribution latency_ms;  ///< per processed frame: arrival to result
  double stage_ms = 0;           ///< the processed frames' stage times (`times_ms`), summed
  RateTimeline processed;        ///< processed frames over the session
  std::vector<Preview> previews;
  std::set<std::string> truth_seen;     ///< sim: labels whole in some frame
  std::set<std::string> truth_in_view;  ///< sim: labels at least partly in some frame
  std::uint64_t frames_saved = 0;
  /// Frames to keep whose files were not written: the writer was still busy with
  /// earlier ones (FrameSaver; the pipeline never waits for the disk).
  std::uint64_t frames_not_saved = 0;
  std::string save_error;  ///< the first frame file that could not be saved
  std::map<std::string, std::uint64_t> models_chosen;   ///< by model
  std::map<std::string, std::uint64_t> frames_flagged;  ///< by flag
  /// Motion refinement: refined - encoder blur (px) of every frame deblurred with
  /// its refined blur, and how many frames had no edges to refine it on.
  ValueDistribution refined_minus_encoder_px;
  std::uint64_t frames_without_motion_edges = 0;
  /// Of those: deblurred with a speed change within the exposure, and with a
  /// speed that wandered within it (belt jitter: block offsets).
  std::uint64_t frames_speed_change = 0, frames_wandering = 0;
  ReadRecordTruth read_record_truth;
  /// Reads by indicative grade ("A" .. "F"), every frame.
  std::map<std::string, std::uint64_t> reads_by_grade;
  SecondPassTally second_pass;
};

/// \brief Reads graded below this (D or F) keep their frame's files, as
/// NO-READs do (output.keep_failed_frames).
inline constexpr double kLowGradeValue = 1.5;

class ResultsStage {
 public:
  /// \brief Results of frames `belt_length_px` long along the motion, for the
  /// session started at `start_ns`; lines to `server` (and `mqtt`, if given),
  /// logs and files to `folder`.
  ResultsStage(const SessionConfig& config, int belt_length_px, std::int64_t start_ns,
               Pipeline& pipeline, SessionFolder& folder, ResultsServer& server,
               MqttPublisher* mqtt = nullptr);

  /// \brief Takes outcomes from `pipeline.outcomes` until it is closed and
  /// empty, then finishes every object; `progress` (may be empty) about twice a second.
  void run(const std::function<void(const Progress&)>& progress);

  /// \brief One outcome, in any order: handled once every earlier index was.
  void take(FrameOutcome outcome);
  /// \brief Every object still on the belt finished and published (the end).
  void finish();
  /// \brief Also shows every frame and object on `view` (set before run()).
  void show_on(LiveView& view) { live_view_ = &view; }

  /// \brief Complete after run() or finish().
  const SessionResults& results() const { return results_; }
  SessionResults& results() { return results_; }

 private:
  void handle(FrameOutcome& f);
  void handle_processed(FrameOutcome& f);
  void publish(std::vector<ObjectResult> finished);
  void count_truth_checks(const std::vector<ReadTruthCheck>& checks);
  void count_second_pass(const nlohmann::json& frame_log);
  Progress progress(std::int64_t now) const;

  const SessionConfig& config_;
  const std::int64_t start_ns_;
  Pipeline& pipeline_;
  SessionFolder& folder_;
  ResultsServer& server_;
  MqttPublisher* mqtt_;
  ObjectTracker tracker_;
  std::map<std::uint64_t, FrameOutcome> waiting_;  ///< by index, until the earlier ones came
  std::uint64_t next_ = 0;
  int first_frames_kept_ = 0;  ///< of output.keep_first_frames, those offered to the writer
  int previews_read_ = 0;
  int previews_failed_ = 0;
  SessionResults results_;
  LiveView* live_view_ = nullptr;
  FrameSaver saver_;  ///< last: its writer stops before the rest goes
};

}  // namespace flutterscan::session
