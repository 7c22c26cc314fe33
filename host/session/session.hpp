#pragma once
// One conveyor session, start to finish (docs/session.md):
//
//   controller armed -> capture thread -> frame matched to its exposure event
//   -> bounded queue -> worker pool (descriptor, deblur + fuse, decode)
//   -> results thread (in capture order: objects tracked on the belt, result
//   lines out, session.jsonl, frame files) -> summary.json, report.html.
//
// The capture thread never blocks: when the queue to the workers is full the
// frame is dropped there, the only place frames are dropped, counted and
// logged. Frames without an exposure event and events without a frame are
// logged, never guessed. A stop request (SIGINT) ends capture; frames already
// matched are finished, files closed, the controller disarmed (LEDs off).

#include <nlohmann/json.hpp>

#include <atomic>
#include <functional>
#include <memory>
#include <string>

#include "session/session_config.hpp"

namespace flutterscan::device {
class VirtualController;
}

namespace flutterscan::session {

class LiveView;

/// \brief Counters for a progress line.
struct Progress {
  std::uint64_t frames_captured = 0;
  std::uint64_t frames_processed = 0;
  std::uint64_t frames_dropped = 0;
  std::uint64_t objects = 0;
  std::uint64_t objects_read = 0;
  double elapsed_s = 0;
  double fps = 0;  ///< processed frames per second so far
};

struct SessionHooks {
  std::function<void(const Progress&)> progress;    ///< about twice a second
  std::function<void(const std::string&)> message;  ///< warnings and notices
  std::function<void(int port)> listening;          ///< the results TCP port, once open
  /// The virtual controller for controller spec "sim" (made here when null).
  std::shared_ptr<device::VirtualController> virtual_controller;
  /// The live view the session keeps up to date (live_view.hpp), or none.
  LiveView* live_view = nullptr;
};

struct SessionOutcome {
  std::string folder;      ///< the session folder (empty if none was made)
  nlohmann::json summary;  ///< as written to summary.json
  std::string error;       ///< empty on success
  bool bad_input = false;  ///< the error is the user's configuration (exit 2)
};

/// \brief Runs a session until the camera ends, a limit is reached or `stop` is set.
SessionOutcome run_session(SessionConfig config, const std::atomic<bool>& stop,
                           const SessionHooks& hooks);

}  // namespace flutterscan::session
