#pragma once
// The `flutterscan device ...` subcommands, one file each (device_*.cpp);
// device.cpp registers them under `device`.

#include <CLI/CLI.hpp>

namespace flutterscan::app {

void add_device_info(CLI::App& device);
void add_device_status(CLI::App& device);
void add_device_set_code(CLI::App& device);
void add_device_select_code(CLI::App& device);
void add_device_set_timing(CLI::App& device);
void add_device_set_mode(CLI::App& device);
void add_device_brightness(CLI::App& device);
void add_device_guard(CLI::App& device);
void add_device_arm(CLI::App& device);
void add_device_disarm(CLI::App& device);
void add_device_selftest(CLI::App& device);
void add_device_save(CLI::App& device);
void add_device_monitor(CLI::App& device);

}  // namespace flutterscan::app
