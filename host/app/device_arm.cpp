// `flutterscan device arm`: start reacting to strobes or generating frames.

#include <cstdio>
#include <memory>

#include "app/device_commands.hpp"
#include "app/device_target.hpp"

namespace flutterscan::app {

void add_device_arm(CLI::App& device) {
  auto target = std::make_shared<DeviceTarget>();
  CLI::App* command = device.add_subcommand("arm", "Start exposing with the selected code");
  add_device_target_options(*command, *target);
  command->callback([target] {
    DeviceSession session(*target);
    value_or_throw(session.client().arm());
    std::printf("armed\n");
  });
}

}  // namespace flutterscan::app
