// `flutterscan device selftest [--step-us N]`: light each LED in turn once.

#include <cstdio>
#include <memory>

#include "app/device_commands.hpp"
#include "app/device_target.hpp"

namespace flutterscan::app {
namespace {

struct SelfTestOptions {
  DeviceTarget target;
  std::uint32_t step_us = 10'000;
};

}  // namespace

void add_device_selftest(CLI::App& device) {
  auto options = std::make_shared<SelfTestOptions>();
  CLI::App* command = device.add_subcommand("selftest", "Light each LED alone in turn, once");
  command->add_option("--step-us", options->step_us, "time each LED is on, microseconds")
      ->check(CLI::Range(protocol::kMinSlotTimeUs, protocol::kMaxSlotTimeUs));
  add_device_target_options(*command, options->target);
  command->callback([options] {
    DeviceSession session(options->target);
    const auto reply = value_or_throw(session.client().self_test(options->step_us));
    std::printf("self test: %u LEDs, %u us each, done in %u us\n", reply.leds_stepped,
                options->step_us, reply.duration_us);
  });
}

}  // namespace flutterscan::app
