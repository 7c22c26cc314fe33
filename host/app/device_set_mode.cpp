// `flutterscan device set-mode slave|master|free [--strobe-active-low]`.

#include <cstdio>
#include <map>
#include <memory>
#include <string>

#include "app/device_commands.hpp"
#include "app/device_target.hpp"

namespace flutterscan::app {
namespace {

struct ModeOptions {
  DeviceTarget target;
  std::string mode;
  bool strobe_active_low = false;
};

void run(const ModeOptions& options) {
  static const std::map<std::string, protocol::SyncMode> kModes = {
      {"slave", protocol::SyncMode::kSlave},
      {"master", protocol::SyncMode::kMaster},
      {"free", protocol::SyncMode::kFreeRun}};
  const auto mode = kModes.find(options.mode);
  if (mode == kModes.end())
    throw UsageError("set-mode: unknown mode '" + options.mode + "' (slave, master or free)");
  DeviceSession session(options.target);
  value_or_throw(session.client().set_mode(mode->second, options.strobe_active_low));
  std::printf("mode %s, strobe active %s\n", options.mode.c_str(),
              options.strobe_active_low ? "low" : "high");
}

}  // namespace

void add_device_set_mode(CLI::App& device) {
  auto options = std::make_shared<ModeOptions>();
  CLI::App* command = device.add_subcommand(
      "set-mode",
      "slave (camera strobe starts exposures), master (controller triggers the "
      "camera) or free (free-running)");
  command->add_option("MODE", options->mode, "slave, master or free")->required();
  command->add_flag("--strobe-active-low", options->strobe_active_low,
                    "the camera's strobe output is active low");
  add_device_target_options(*command, options->target);
  command->callback([options] { run(*options); });
}

}  // namespace flutterscan::app
