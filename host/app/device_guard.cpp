// `flutterscan device guard --on-time-us US... --duty-permille P...`: the
// thermal guard's limits per LED (one value: every LED). The controller
// refuses limits above the ceiling compiled into its firmware (exit 2).

#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "app/device_commands.hpp"
#include "app/device_target.hpp"

namespace flutterscan::app {
namespace {

struct GuardOptions {
  DeviceTarget target;
  std::vector<long long> on_time_us;
  std::vector<long long> duty_permille;
};

/// `values` spread over `leds` LEDs (one value: all of them); `what` names the option.
std::vector<long long> per_led(const std::vector<long long>& values, int leds, const char* what) {
  if (values.size() == 1) return std::vector<long long>(static_cast<std::size_t>(leds), values[0]);
  if (static_cast<int>(values.size()) != leds)
    throw UsageError(std::string("guard: ") + what + " has " + std::to_string(values.size()) +
                     " values, the controller has " + std::to_string(leds) +
                     " LEDs (give one value for all, or one per LED)");
  return values;
}

void run(const GuardOptions& options) {
  DeviceSession session(options.target);
  const int leds = session.client().info().led_count;
  const auto on_time = per_led(options.on_time_us, leds, "--on-time-us");
  const auto duty = per_led(options.duty_permille, leds, "--duty-permille");
  protocol::SetGuardRequest request{};
  for (int led = 0; led < leds; ++led) {
    const auto k = static_cast<std::size_t>(led);
    if (on_time[k] < 1 || on_time[k] > protocol::kMaxGuardOnTimeUs)
      throw UsageError("guard: --on-time-us of LED " + std::to_string(led) + ": " +
                       std::to_string(on_time[k]) + " is outside 1.." +
                       std::to_string(protocol::kMaxGuardOnTimeUs));
    if (duty[k] < 1 || duty[k] > protocol::kDutyFullScale)
      throw UsageError("guard: --duty-permille of LED " + std::to_string(led) + ": " +
                       std::to_string(duty[k]) + " is outside 1..1000");
    request.max_on_time_us[k] = static_cast<std::uint32_t>(on_time[k]);
    request.max_duty_permille[k] = static_cast<std::uint16_t>(duty[k]);
  }
  value_or_throw(session.client().set_guard(request));
  std::printf("guard");
  for (int led = 0; led < leds; ++led)
    std::printf(" LED %d: %lld us, %lld per mille;", led, on_time[static_cast<std::size_t>(led)],
                duty[static_cast<std::size_t>(led)]);
  std::printf("\n");
}

}  // namespace

void add_device_guard(CLI::App& device) {
  auto options = std::make_shared<GuardOptions>();
  CLI::App* command = device.add_subcommand(
      "guard", "Thermal guard limits per LED (at most the ceiling compiled into the firmware)");
  command->add_option("--on-time-us", options->on_time_us,
                      "longest joined run per LED, microseconds (one value: every LED)")
      ->required()
      ->expected(1, protocol::kMaxCodeLeds);
  command->add_option("--duty-permille", options->duty_permille,
                      "largest energy duty per LED, per mille (one value: every LED)")
      ->required()
      ->expected(1, protocol::kMaxCodeLeds);
  add_device_target_options(*command, options->target);
  command->callback([options] { run(*options); });
}

}  // namespace flutterscan::app
