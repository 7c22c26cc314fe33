#include "bench/live_view_runs.hpp"

#include <httplib.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <optional>
#include <thread>
#include <vector>

#include "session/live_view.hpp"
#include "session/live_view_server.hpp"
#include "session/session.hpp"

namespace flutterscan::bench {

namespace {

double median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

/// Polls the live view on `port` as the page does until `done`; counts what it
/// got while the session was armed (its frames streaming), and for how long.
struct PageClient {
  std::uint64_t states = 0, pictures = 0;
  double armed_s = 0;
  void run(int port, const std::atomic<bool>& done) {
    httplib::Client client("127.0.0.1", port);
    std::int64_t shown = -1;
    std::optional<std::chrono::steady_clock::time_point> first;
    while (!done) {
      if (auto r = client.Get("/state.json"); r && r->status == 200) {
        const auto s = nlohmann::json::parse(r->body, nullptr, false);
        if (!s.is_discarded() && s["state"] == "armed") {
          const auto now = std::chrono::steady_clock::now();
          if (!first) first = now;
          armed_s = std::chrono::duration<double>(now - *first).count();
          ++states;
          if (s["picture"].is_object() && s["picture"]["sequence"].get<std::int64_t>() != shown) {
            shown = s["picture"]["sequence"].get<std::int64_t>();
            const std::string query = "?frame=" + std::to_string(shown);
            client.Get("/frame/captured.jpg" + query);
            client.Get("/frame/fused.jpg" + query);
            ++pictures;
          }
        }
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(250));
    }
  }
};

}  // namespace

LiveViewRun run_live_view_case(const session::SessionConfig& config, bool live) {
  LiveViewRun run;
  session::LiveView view;
  session::LiveViewServer server(view);
  session::SessionHooks hooks;
  PageClient page;
  std::atomic<bool> done{false};
  std::thread client;
  if (live) {
    if (auto p = server.listen({"127.0.0.1", 0}); !p.empty()) {
      run.error = p;
      return run;
    }
    hooks.live_view = &view;
    client = std::thread([&] { page.run(server.port(), done); });
  }
  std::atomic<bool> stop{false};
  const auto outcome = session::run_session(config, stop, hooks);
  done = true;
  if (client.joinable()) client.join();
  run.error = outcome.error;
  run.summary = outcome.summary;
  if (page.armed_s > 0) {
    // n answers span n - 1 intervals.
    run.states_per_s = static_cast<double>(page.states - 1) / page.armed_s;
    run.pictures_per_s = static_cast<double>(page.pictures) / page.armed_s;
  }
  if (live) {
    const auto s = view.state();
    const double seconds = outcome.summary.value("duration_s", 0.0);
    if (seconds > 0) run.encoded_per_s = s["live_view"]["pictures"].get<double>() / seconds;
    run.picture_cpu_ms = s["live_view"]["picture_cpu_ms_mean"].get<double>();
  }
  return run;
}

nlohmann::json live_view_update_costs() {
  session::LiveView view;
  session::Pipeline pipeline(4);
  session::FrameOutcome f;
  f.processed = true;
  f.latency_ms = 40;
  f.log = {{"flags", {"no-read"}}, {"decoded", nlohmann::json::array()}, {"decode_windows", 2}};
  const int n = 20000;
  std::vector<double> update_us, state_us;
  for (int i = 0; i < n; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    view.frame_done(f, pipeline);
    view.offer_picture(f);  // no frame to take: as between two pictures
    const auto t1 = std::chrono::steady_clock::now();
    update_us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
    if (i % 7 == 0) {
      session::ObjectResult o;
      o.id = static_cast<std::uint64_t>(i);
      o.value = i % 2 ? "ABC-123" : "";
      o.frames_seen = 4;
      o.frames_decoded = 3;
      view.object_done(o);
    }
  }
  for (int i = 0; i < 200; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    const std::string text = view.state().dump();
    state_us.push_back(
        std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
    if (text.empty()) return {};
  }
  return {{"update_us_per_frame", median(update_us)}, {"state_us", median(state_us)}};
}

}  // namespace flutterscan::bench
