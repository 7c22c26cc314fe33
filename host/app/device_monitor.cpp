// `flutterscan device monitor [--arm] [--count N] [--seconds S]`: prints every
// exposure event as it arrives, and every gap in the frame counter; Ctrl-C stops.

#include <csignal>
#include <cstdio>
#include <memory>
#include <string>

#include "app/device_commands.hpp"
#include "app/device_target.hpp"

namespace flutterscan::app {
namespace {

volatile std::sig_atomic_t g_interrupted = 0;

extern "C" void on_interrupt(int) {
  g_interrupted = 1;
}

struct MonitorOptions {
  DeviceTarget target;
  bool arm = false;
  long count = 0;
  double seconds = 0;
  double sim_rate_hz = 30;
  std::uint32_t sim_exposure_us = 10'000;
};

std::string flag_names(std::uint16_t flags) {
  std::string out;
  auto add = [&](std::uint16_t bit, const char* name) {
    if (flags & bit) out += (out.empty() ? "" : ",") + std::string(name);
  };
  add(protocol::kEventMissedTrigger, "missed-trigger");
  add(protocol::kEventOverrun, "overrun");
  add(protocol::kEventCodeSwitched, "code-switched");
  add(protocol::kEventGuardHit, "guard-hit");
  add(protocol::kEventSlotTimeClamped, "slot-time-clamped");
  return out.empty() ? "-" : out;
}

void run(const MonitorOptions& options) {
  DeviceSession session(options.target);
  auto& client = session.client();
  if (options.arm) {
    value_or_throw(client.arm());
  } else if (value_or_throw(client.status()).state ==
             static_cast<std::uint8_t>(protocol::ControllerState::kIdle)) {
    std::fprintf(stderr,
                 "flutterscan: the controller is idle: no events until it is armed "
                 "(device arm, or monitor --arm)\n");
  }
  if (session.sim() != nullptr)
    session.sim()->set_camera(options.sim_rate_hz, options.sim_exposure_us);
  g_interrupted = 0;
  const auto previous_handler = std::signal(SIGINT, on_interrupt);
  std::printf("%10s %14s %8s %5s %5s %9s %8s  %s\n", "frame", "start_us", "slot_us", "code",
              "slots", "encoder", "pulse_us", "flags");
  std::fflush(stdout);
  long received = 0;
  const auto start = std::chrono::steady_clock::now();
  auto time_left = [&] {
    return options.seconds <= 0 ||
           std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() <
               options.seconds;
  };
  while (!g_interrupted && (options.count <= 0 || received < options.count) && time_left()) {
    const auto notice = client.next_event(std::chrono::milliseconds(100));
    if (!notice) continue;
    if (notice->frames_missing_before > 0)
      std::printf("!! %u exposure event(s) lost before frame %u\n", notice->frames_missing_before,
                  notice->event.frame_counter);
    const auto& e = notice->event;
    std::printf("%10u %14llu %8u %5u %5u %+9d %8u  %s\n", e.frame_counter,
                static_cast<unsigned long long>(e.start_time_us), e.slot_time_us, e.code_id,
                e.slot_count, e.encoder_delta, e.pulse_width_us, flag_names(e.flags).c_str());
    std::fflush(stdout);
    ++received;
  }
  std::signal(SIGINT, previous_handler);
  if (session.sim() != nullptr) session.sim()->set_camera(0, options.sim_exposure_us);
  const auto stats = client.stats();
  std::fprintf(stderr, "flutterscan: %llu events, %llu exposures without an event\n",
               static_cast<unsigned long long>(stats.events),
               static_cast<unsigned long long>(stats.frames_missing));
  if (options.arm) value_or_throw(client.disarm());
  if (!client.connected()) throw RuntimeFailure(client.description() + " is gone");
}

}  // namespace

void add_device_monitor(CLI::App& device) {
  auto options = std::make_shared<MonitorOptions>();
  CLI::App* command =
      device.add_subcommand("monitor", "Print exposure events as they arrive (Ctrl-C stops)");
  command->add_flag("--arm", options->arm, "arm first, disarm at the end");
  command->add_option("--count", options->count, "stop after this many events")
      ->check(CLI::PositiveNumber);
  command->add_option("--seconds", options->seconds, "stop after this long")
      ->check(CLI::PositiveNumber);
  command
      ->add_option("--sim-rate-hz", options->sim_rate_hz,
                   "--device sim: the virtual camera's frame rate")
      ->check(CLI::Range(0.1, 1000.0));
  command
      ->add_option("--sim-exposure-us", options->sim_exposure_us,
                   "--device sim: the virtual camera's exposure")
      ->check(CLI::Range(1u, 1'000'000u));
  add_device_target_options(*command, options->target);
  command->callback([options] { run(*options); });
}

}  // namespace flutterscan::app
