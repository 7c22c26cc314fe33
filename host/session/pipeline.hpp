#pragma once
// What travels between the session's stages (docs/session.md, "The pipeline"):
//
//   capture + matching --FrameJob--> workers --FrameOutcome--> results
//                      \--FrameOutcome (no event, dropped)---/
//
// The queue to the workers is bounded (queue_depth): the capture thread never
// waits on it and drops the frame when it is full. Every frame index reaches
// the results thread exactly once as a FrameOutcome, processed or not.

#include <nlohmann/json.hpp>

#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

#include "capture/camera_source.hpp"
#include "imaging/image.hpp"
#include "session/bounded_queue.hpp"
#include "session/frame_matcher.hpp"
#include "session/object_tracker.hpp"

namespace flutterscan::session {

/// \brief A frame matched to its event, on its way to a worker.
struct FrameJob {
  std::uint64_t index = 0;  ///< capture order, from 0, every frame matched or not
  capture::Frame frame;
  ExposureRecord event;
  double residual_us = 0;  ///< the event's start minus the clock fit's prediction
  double travel_px = 0;    ///< belt travel since the first event, image pixels
  std::string match_note;  ///< the matcher's note (a re-derived offset), if any
  /// Frames still waiting for a worker when one took this frame (worker_pool.cpp).
  std::size_t waiting_behind = 0;
};

/// \brief A read checked against the simulator's truth (sim frames only): the
/// record's corners, module size and symbology identifier against the label's.
struct ReadTruthCheck {
  std::string value;
  bool found = false;          ///< a label of this value lies whole in the frame
  double corner_error_px = 0;  ///< the worst of the four corners, either axis
  double module_error = 0;     ///< |measured - true| / true
  bool symbology_id_matches = false;
};

/// \brief What the results thread gets for every frame index, processed or not.
struct FrameOutcome {
  std::uint64_t index = 0;
  std::uint64_t sequence = 0;
  bool processed = false;
  nlohmann::json log;  ///< the frame's line in session.jsonl
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
  std::vector<ReadTruthCheck> truth_checks;  ///< one per read, on sim frames
};

/// \brief The queues between the stages and the frame counters they keep.
struct Pipeline {
  explicit Pipeline(std::size_t queue_depth) : jobs(queue_depth) {}
  BoundedQueue<FrameJob> jobs;                                ///< capture -> workers
  BoundedQueue<FrameOutcome> outcomes{std::size_t{1} << 30};  ///< every stage -> results
  std::atomic<std::uint64_t> frames_captured{0};
  std::atomic<std::uint64_t> frames_dropped{0};
  std::atomic<std::uint64_t> frames_processed{0};
  std::atomic<std::uint64_t> processing_errors{0};
};

}  // namespace flutterscan::session
