#pragma once
// Every subcommand registers itself on the CLI11 tree; each lives in its own file.

#include <CLI/CLI.hpp>

namespace flutterscan::app {

/// \brief `flutterscan codes ...`: the code toolkit (codes.cpp).
void add_codes_command(CLI::App& app);
void add_codes_score(CLI::App& codes);
void add_codes_search(CLI::App& codes);
void add_codes_plot(CLI::App& codes);
void add_codes_list(CLI::App& codes);
/// \brief `flutterscan simulate` (simulate.cpp).
void add_simulate(CLI::App& app);
/// \brief `flutterscan deblur` (deblur.cpp).
void add_deblur(CLI::App& app);
/// \brief `flutterscan bench` (bench.cpp).
void add_bench(CLI::App& app);
/// \brief `flutterscan calibrate ...` (calibrate.cpp).
void add_calibrate(CLI::App& app);
/// \brief `flutterscan devices` (devices.cpp).
void add_devices(CLI::App& app);
/// \brief `flutterscan device ...` (device.cpp, device_*.cpp).
void add_device_command(CLI::App& app);
/// \brief `flutterscan flash` (flash.cpp).
void add_flash(CLI::App& app);

/// \brief `flutterscan scan` (scan.cpp).
void add_scan(CLI::App& app);
/// \brief `flutterscan demo` (demo.cpp).
void add_demo(CLI::App& app);
/// \brief `flutterscan cameras` (cameras.cpp).
void add_cameras(CLI::App& app);
/// \brief `flutterscan replay` (replay.cpp).
void add_replay(CLI::App& app);

}  // namespace flutterscan::app
