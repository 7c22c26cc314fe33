// hil_bench: figures through the umockdev mock (not a test; tools/bench runs it
// as the `hil` part). Each figure is one run of the HIL harness:
//   - command round-trip latency: N GetStatus commands through the client
//     (hidraw backend) -> median and p99;
//   - exposure events per second sustained without a gap: strobes at rising
//     rates (a 3-slot code of 10 us slots) until the host misses an event;
//   - flash throughput: `flutterscan flash` and `dfu-util -D` of a 64 KiB image.
// Everything here crosses umockdev's preload library and a Unix socket per
// ioctl/read/write: the figures describe the mock, not real USB.
//
//   hil_bench [--count N] [--csv FILE]
//   hil_bench --inside latency|events ...   (what the harness runs)

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "device/controller_client.hpp"
#include "device/usb_discovery.hpp"
#include "flutterscan/common/protocol.hpp"

extern char** environ;

namespace {

using namespace flutterscan;
using Clock = std::chrono::steady_clock;

// ---------------------------------------------------------------------------
// Inside the harness

std::unique_ptr<device::ControllerClient> connect_or_die() {
  auto found = device::find_controllers();
  if (!found) {
    std::cerr << "hil_bench: " << found.error().message << "\n";
    std::exit(1);
  }
  auto picked =
      device::pick_controller(found.value(), std::nullopt, device::DeviceMode::kApplication);
  if (!picked) {
    std::cerr << "hil_bench: " << picked.error().message << "\n";
    std::exit(1);
  }
  device::ClientOptions options;
  options.reconnect = false;
  auto client =
      device::ControllerClient::connect(device::hid_opener(picked.value().serial), options);
  if (!client) {
    std::cerr << "hil_bench: " << client.error().message << "\n";
    std::exit(1);
  }
  return std::move(client.value());
}

int inside_latency(int count) {
  auto client = connect_or_die();
  std::vector<double> us;
  for (int i = 0; i < count + 20; ++i) {
    const auto t0 = Clock::now();
    auto s = client->status();
    const auto t1 = Clock::now();
    if (!s) {
      std::cerr << "hil_bench: status: " << s.error().message << "\n";
      return 1;
    }
    if (i >= 20) us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
  }
  std::sort(us.begin(), us.end());
  std::cout << "latency_median_us=" << us[us.size() / 2] << "\n"
            << "latency_p99_us=" << us[us.size() * 99 / 100] << "\n";
  return 0;
}

int inside_events(int count) {
  auto client = connect_or_die();
  auto code = LedCode::parse("124", client->info().led_count, CodeRule::kOneOfN);
  protocol::SetTimingRequest timing{};
  timing.slot_time_us = 10;
  if (!code || !client->set_code(0, code.value(), true) || !client->select_code(0) ||
      !client->set_timing(timing) || !client->set_mode(protocol::SyncMode::kSlave, false) ||
      !client->arm()) {
    std::cerr << "hil_bench: setting up the exposure failed\n";
    return 1;
  }
  int received = 0;
  Clock::time_point first{}, last{};
  while (received < count) {
    auto e = client->next_event(std::chrono::milliseconds(2000));
    if (!e) break;
    if (received == 0) first = Clock::now();
    last = Clock::now();
    ++received;
  }
  client->disarm();
  const double s = std::chrono::duration<double>(last - first).count();
  std::cout << "events=" << received << "\nframes_missing=" << client->stats().frames_missing
            << "\nevents_per_s=" << (s > 0 ? (received - 1) / s : 0) << "\n";
  return 0;
}

// ---------------------------------------------------------------------------
// Driving the harness

std::pair<int, std::string> run(const std::vector<std::string>& argv) {
  char path[] = "/tmp/hil_bench_XXXXXX";
  const int fd = mkstemp(path);
  close(fd);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, path, O_WRONLY | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  std::vector<std::string> copy = argv;
  std::vector<char*> args;
  for (auto& a : copy) args.push_back(a.data());
  args.push_back(nullptr);
  pid_t pid = -1;
  int status = -1;
  if (posix_spawnp(&pid, args[0], &actions, nullptr, args.data(), environ) == 0)
    waitpid(pid, &status, 0);
  posix_spawn_file_actions_destroy(&actions);
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  unlink(path);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, s.str()};
}

std::string value(const std::string& output, const std::string& key) {
  std::istringstream in(output);
  std::string line;
  while (std::getline(in, line))
    if (line.rfind(key + "=", 0) == 0) return line.substr(key.size() + 1);
  return "";
}

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

/// dfu-util's -d: the application's and the bootloader's VID:PID (protocol.hpp),
/// "1209:0001,1209:0002".
std::string dfu_util_devices() {
  char text[32];
  std::snprintf(text, sizeof text, "%04x:%04x,%04x:%04x", protocol::kUsbVendorId,
                protocol::kUsbProductIdApplication, protocol::kUsbVendorId,
                protocol::kUsbProductIdBootloader);
  return text;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"hil_bench: latency, event rate and flash throughput through the umockdev mock"};
  std::string inside;
  int count = 1000;
  std::string csv_path;
  app.add_option("--inside", inside, "Run one measurement as the program under the harness")
      ->check(CLI::IsMember({"latency", "events"}));
  app.add_option("--count", count, "Commands (latency) or events (event rate) per run");
  app.add_option("--csv", csv_path, "Also write the figures as CSV");
  CLI11_PARSE(app, argc, argv);
  if (inside == "latency") return inside_latency(count);
  if (inside == "events") return inside_events(count);

  const std::string self = argv[0];
  std::vector<std::pair<std::string, std::string>> rows;  // figure, value
  std::cout << "All figures through the umockdev mock (preload library + a Unix socket per\n"
               "ioctl/read/write), not real USB. Machine: "
            << sysconf(_SC_NPROCESSORS_ONLN) << " cores.\n\n";

  // Latency.
  {
    auto [rc, out] =
        run({HIL_HARNESS, "--", self, "--inside", "latency", "--count", std::to_string(count)});
    if (rc == 77) {
      std::cout << "umockdev cannot run here: no figures\n";
      return 77;
    }
    std::cout << "GetStatus round trip (" << count << " commands, hidraw backend): median "
              << value(out, "latency_median_us") << " us, p99 " << value(out, "latency_p99_us")
              << " us\n";
    if (rc != 0) std::cout << out;
    rows.push_back({"latency_median_us", value(out, "latency_median_us")});
    rows.push_back({"latency_p99_us", value(out, "latency_p99_us")});
  }

  // Event rate: rising strobe rates until an event is missed.
  {
    std::string best = "0";
    for (int period_us : {2000, 1000, 800, 600, 500, 400, 300, 200}) {
      const int n = std::max(200, 2'000'000 / period_us);  // about 2 s of strobes
      auto [rc, out] = run({HIL_HARNESS, "--strobes", std::to_string(n), "--strobe-width-us",
                            std::to_string(period_us / 4), "--strobe-period-us",
                            std::to_string(period_us), "--timeout-s", "60", "--", self, "--inside",
                            "events", "--count", std::to_string(n)});
      const std::string got = value(out, "events");
      const std::string missing = value(out, "frames_missing");
      const std::string rate = value(out, "events_per_s");
      std::cout << "strobes every " << period_us << " us: " << got << "/" << n
                << " events, missing " << missing << ", " << rate << " events/s\n";
      if (rc != 0 || got != std::to_string(n) || missing != "0") break;
      best = std::to_string(1'000'000 / period_us);  // the strobe rate, on the board's clock
    }
    std::cout << "exposure events per second sustained without a gap (strobe rate): " << best
              << "\n";
    rows.push_back({"events_per_s_no_gap", best});
  }

  // Flash throughput.
  {
    const std::string image = "/tmp/hil_bench_app.bin";
    run({HIL_MAKE_IMAGE, image, "--size", "65536", "--version", "0.2.0"});
    auto t0 = Clock::now();
    auto [rc1, out1] =
        run({HIL_HARNESS, "--timeout-s", "120", "--", FLUTTERSCAN_BINARY, "flash", image});
    const double s1 = seconds_since(t0);
    t0 = Clock::now();
    auto [rc2, out2] = run({HIL_HARNESS, "--timeout-s", "120", "--", DFU_UTIL, "-d",
                            dfu_util_devices(), "-D", image, "-R"});
    const double s2 = seconds_since(t0);
    char a[64], b[64];
    std::snprintf(a, sizeof a, "%.1f", 64 / s1);
    std::snprintf(b, sizeof b, "%.1f", 64 / s2);
    std::cout << "flutterscan flash, 64 KiB: " << s1 << " s (" << a << " KiB/s, exit " << rc1
              << ")\n"
              << "dfu-util -D -R, 64 KiB: " << s2 << " s (" << b << " KiB/s, exit " << rc2
              << "; honours bwPollTimeout: erase and program estimates)\n";
    rows.push_back({"flash_flutterscan_kib_per_s", a});
    rows.push_back({"flash_dfu_util_kib_per_s", b});
    unlink(image.c_str());
  }

  if (!csv_path.empty()) {
    std::ofstream csv(csv_path);
    csv << "figure,value\n";
    for (const auto& [k, v] : rows) csv << k << "," << v << "\n";
  }
  return 0;
}
