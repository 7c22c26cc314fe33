// `flutterscan device brightness R G B`: per-LED brightness, per mille.

#include <cstdio>
#include <memory>
#include <vector>

#include "app/device_commands.hpp"
#include "app/device_target.hpp"

namespace flutterscan::app {
namespace {

struct BrightnessOptions {
  DeviceTarget target;
  std::vector<int> permille;
};

void run(const BrightnessOptions& options) {
  protocol::SetBrightnessRequest request{};
  for (std::size_t i = 0; i < options.permille.size(); ++i) {
    const int value = options.permille[i];
    if (value < 0 || value > protocol::kBrightnessFullScale)
      throw UsageError("brightness of LED " + std::to_string(i) + ": " + std::to_string(value) +
                       " is outside 0..1000 (per mille)");
    request.permille[i] = static_cast<std::uint16_t>(value);
  }
  DeviceSession session(options.target);
  if (static_cast<int>(options.permille.size()) != session.client().info().led_count)
    throw UsageError("brightness: " + std::to_string(options.permille.size()) +
                     " values given, the controller has " +
                     std::to_string(session.client().info().led_count) + " LEDs");
  value_or_throw(session.client().set_brightness(request));
  std::printf("brightness");
  for (const int value : options.permille) std::printf(" %d", value);
  std::printf(" per mille\n");
}

}  // namespace

void add_device_brightness(CLI::App& device) {
  auto options = std::make_shared<BrightnessOptions>();
  CLI::App* command =
      device.add_subcommand("brightness", "Per-LED brightness in per mille (R G B: 0..1000 each)");
  command->add_option("R G B", options->permille, "one value per LED, 0..1000")
      ->required()
      ->expected(1, protocol::kMaxCodeLeds);
  add_device_target_options(*command, options->target);
  command->callback([options] { run(*options); });
}

}  // namespace flutterscan::app
