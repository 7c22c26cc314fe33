#include "session/bench/live_view_runs.hpp"

#include <httplib.h>
#include <sys/resource.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <ctime>
#include <thread>
#include <vector>

#include "session/live_view.hpp"
#include "session/live_view_server.hpp"
#include "session/session.hpp"

namespace flutterscan::bench {

namespace {

double process_cpu_ms() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) * 1e3 +
         static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec) * 1e-3;
}

double thread_cpu_ms() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) * 1e3 + static_cast<double>(t.tv_nsec) * 1e-6;
}

double median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

/// Polls the live view on `port` as the page does until `done`; counts what it got.
struct PageClient {
  std::uint64_t states = 0, pictures = 0;
  double cpu_ms = 0;
  void run(int port, const std::atomic<bool>& done) {
    const double start = thread_cpu_ms();
    httplib::Client client("127.0.0.1", port);
    std::int64_t shown = -1;
    while (!done) {
      if (auto r = client.Get("/state.json"); r && r->status == 200) {
        ++states;
        const auto s = nlohmann::json::parse(r->body, nullptr, false);
        if (!s.is_discarded() && s["picture"].is_object() &&
            s["picture"]["sequence"].get<std::int64_t>() != shown) {
          shown = s["picture"]["sequence"].get<std::int64_t>();
          client.Get("/frame/captured.png");
          client.Get("/frame/fused.png");
          ++pictures;
        }
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(250));
    }
    cpu_ms = thread_cpu_ms() - start;
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
  const double cpu_start = process_cpu_ms();
  const auto outcome = session::run_session(config, stop, hooks);
  const double cpu_ms = process_cpu_ms() - cpu_start;
  done = true;
  if (client.joinable()) client.join();
  run.error = outcome.error;
  run.summary = outcome.summary;
  const double frames = outcome.summary.value("frames_processed", 0.0);
  const double seconds = outcome.summary.value("duration_s", 0.0);
  run.process_cpu_ms_per_frame = frames > 0 ? (cpu_ms - page.cpu_ms) / frames : 0;
  if (seconds > 0) {
    run.states_per_s = static_cast<double>(page.states) / seconds;
    run.pictures_per_s = static_cast<double>(page.pictures) / seconds;
  }
  if (live) run.picture_cpu_ms = view.state()["live_view"]["picture_cpu_ms_mean"].get<double>();
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
