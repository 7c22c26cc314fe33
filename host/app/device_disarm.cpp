// `flutterscan device disarm`: stop, every LED off, leave a fault.

#include <cstdio>
#include <memory>

#include "app/device_commands.hpp"
#include "app/device_target.hpp"

namespace flutterscan::app {

void add_device_disarm(CLI::App& device) {
  auto target = std::make_shared<DeviceTarget>();
  CLI::App* command = device.add_subcommand("disarm", "Stop exposing; every LED off");
  add_device_target_options(*command, *target);
  command->callback([target] {
    DeviceSession session(*target);
    value_or_throw(session.client().disarm());
    std::printf("disarmed\n");
  });
}

}  // namespace flutterscan::app
