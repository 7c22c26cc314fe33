#include "bench/soak_run.hpp"

#include <malloc.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <mutex>
#include <thread>
#include <vector>

#include "session/session.hpp"

namespace flutterscan::bench {

namespace {

struct Sample {
  double t_s = 0;
  double rss_mb = 0;   ///< resident set
  double heap_mb = 0;  ///< bytes malloc has handed out and not had back
  std::uint64_t frames = 0;
};

double resident_mb() {
  std::ifstream statm("/proc/self/statm");
  std::uint64_t size = 0, resident = 0;
  statm >> size >> resident;
  return static_cast<double>(resident) * static_cast<double>(sysconf(_SC_PAGESIZE)) / 1e6;
}

double heap_in_use_mb() {
  const struct mallinfo2 m = mallinfo2();
  return static_cast<double>(m.uordblks + m.hblkhd) / 1e6;
}

/// Least-squares slope of `y` over `t` (per second), samples with t >= `from_s`.
double slope_per_s(const std::vector<Sample>& samples, double Sample::*y, double from_s) {
  double n = 0, st = 0, sy = 0, stt = 0, sty = 0;
  for (const auto& s : samples) {
    if (s.t_s < from_s) continue;
    n += 1;
    st += s.t_s;
    sy += s.*y;
    stt += s.t_s * s.t_s;
    sty += s.t_s * (s.*y);
  }
  const double d = n * stt - st * st;
  return n >= 3 && d > 0 ? (n * sty - st * sy) / d : 0.0;
}

}  // namespace

int soak_table(const session::SessionConfig& config, double sample_s, const std::string& csv) {
  std::vector<Sample> samples;
  std::mutex mutex;
  std::condition_variable wake;
  bool done = false;
  std::atomic<std::uint64_t> frames{0};
  const auto start = std::chrono::steady_clock::now();
  std::thread sampler([&] {
    std::unique_lock lock(mutex);
    for (;;) {
      const double t =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      samples.push_back({t, resident_mb(), heap_in_use_mb(), frames.load()});
      if (wake.wait_for(lock, std::chrono::duration<double>(sample_s), [&] { return done; })) break;
    }
  });
  session::SessionHooks hooks;
  hooks.progress = [&](const session::Progress& p) { frames = p.frames_processed; };
  std::atomic<bool> stop{false};
  const auto outcome = session::run_session(config, stop, hooks);
  {
    std::lock_guard lock(mutex);
    done = true;
  }
  wake.notify_all();
  sampler.join();
  if (!csv.empty()) {  // the samples, whatever became of the session
    std::ofstream out(csv);
    out << "t_s,rss_mb,heap_mb,frames_processed\n";
    for (const auto& s : samples)
      out << s.t_s << ',' << s.rss_mb << ',' << s.heap_mb << ',' << s.frames << '\n';
  }
  if (!outcome.error.empty()) {
    std::cerr << "session_bench --soak: " << outcome.error << "\n";
    return 1;
  }
  const auto& s = outcome.summary;
  const double minutes = s.value("duration_s", 0.0) / 60;
  std::cout << "soak: " << s.value("frame_size", "") << " at 60 fps for " << minutes
            << " min, memory sampled every " << sample_s << " s\n\n"
            << "| t (min) | RSS (MB) | heap in use (MB) | frames processed |\n|---|---|---|---|\n";
  double next_row_s = 0;
  for (const auto& x : samples)
    if (x.t_s >= next_row_s || &x == &samples.back()) {
      char row[160];
      std::snprintf(row, sizeof row, "| %.1f | %.1f | %.1f | %llu |\n", x.t_s / 60, x.rss_mb,
                    x.heap_mb, static_cast<unsigned long long>(x.frames));
      std::cout << row;
      next_row_s = x.t_s + std::max(60.0, minutes * 60 / 12);
    }
  const double first_minute = std::min(60.0, samples.back().t_s / 2);
  std::cout << "\ngrowth after the first minute (least squares): RSS "
            << slope_per_s(samples, &Sample::rss_mb, first_minute) * 3600 << " MB/h, heap in use "
            << slope_per_s(samples, &Sample::heap_mb, first_minute) * 3600 << " MB/h\n"
            << "frames captured " << s["frames_captured"] << ", processed " << s["frames_processed"]
            << ", dropped " << s["frames_dropped"] << ", failed " << s["frames_failed"]
            << "; objects " << s["objects"] << ", read " << s["objects_read"] << "; latency p50 "
            << s["latency_ms_p50"] << " ms, p99 " << s["latency_ms_p99"] << " ms\n";
  return 0;
}

}  // namespace flutterscan::bench
