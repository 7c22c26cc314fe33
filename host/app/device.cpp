// `flutterscan device <command>`: talk to one LED controller.

#include "app/commands.hpp"
#include "app/device_commands.hpp"

namespace flutterscan::app {

void add_device_command(CLI::App& app) {
  CLI::App* device = app.add_subcommand(
      "device",
      "Talk to one LED controller (--device SERIAL, or --device sim for the virtual one)");
  device->require_subcommand(1);
  add_device_info(*device);
  add_device_status(*device);
  add_device_set_code(*device);
  add_device_select_code(*device);
  add_device_set_timing(*device);
  add_device_set_mode(*device);
  add_device_brightness(*device);
  add_device_guard(*device);
  add_device_arm(*device);
  add_device_disarm(*device);
  add_device_selftest(*device);
  add_device_save(*device);
  add_device_monitor(*device);
}

}  // namespace flutterscan::app
