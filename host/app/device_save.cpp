// `flutterscan device save`: store codes and settings in the controller's flash.

#include <cstdio>
#include <memory>

#include "app/device_commands.hpp"
#include "app/device_target.hpp"

namespace flutterscan::app {

void add_device_save(CLI::App& device) {
  auto target = std::make_shared<DeviceTarget>();
  CLI::App* command =
      device.add_subcommand("save", "Store codes and settings in flash (loaded at power-on)");
  add_device_target_options(*command, *target);
  command->callback([target] {
    DeviceSession session(*target);
    const auto reply = value_or_throw(session.client().save_config());
    std::printf("saved %u bytes (CRC-32 %08X)\n", reply.bytes_written, reply.crc32);
  });
}

}  // namespace flutterscan::app
