#pragma once
// session_bench --live-view: what the live view (scan|demo --http) costs the
// pipeline. The same session run without and with it, a client polling it as
// the page does (state four times a second, both pictures each time a newer
// frame was encoded) on its own thread; and the live view's own work timed
// apart: a picture on its thread (CPU time), the results thread's per-frame
// update, one state for the page.

#include <nlohmann/json.hpp>

#include <string>

#include "session/session_config.hpp"

namespace flutterscan::bench {

struct LiveViewRun {
  nlohmann::json summary;
  double states_per_s = 0;    ///< state.json answers while armed, per second
  double pictures_per_s = 0;  ///< newer pictures the client fetched while armed, per second
  double encoded_per_s = 0;   ///< pictures the live view encoded, per second of the session
  double picture_cpu_ms = 0;  ///< the picture thread's CPU time per picture
  std::string error;
};

/// \brief Runs `config` with the live view and its polling client when `live`, else bare.
LiveViewRun run_live_view_case(const session::SessionConfig& config, bool live);

/// \brief Microseconds of the results thread's update per frame (frame_done and
/// offer_picture while a picture is in progress) and of one state for the page (state() and
/// its JSON text), medians over many calls.
nlohmann::json live_view_update_costs();

}  // namespace flutterscan::bench
