#pragma once
// Command-line arguments shared by the `codes` subcommands: code strings or
// library names, and the light-model flags of the joint and mse merits.

#include <CLI/CLI.hpp>

#include <string>
#include <vector>

#include "codes/merits.hpp"

namespace flutterscan::app {

/// \brief Flags that set MeritSettings.
struct MeritFlags {
  double electrons = 3000;
  double cap = 3;
  double read_noise = 4;
  std::string crosstalk;
  double mse_eps = 10;
  int single_pad = 256;
};

/// \brief Adds --electrons, --cap, --read-noise, --crosstalk, --eps, --pad.
void add_merit_flags(CLI::App& command, MeritFlags& flags);

/// \brief Checks the flags and builds the settings; throws UsageError naming the bad flag.
codes::MeritSettings merit_settings(const MeritFlags& flags);

/// \brief Parses "m00,m01,m02;m10,..." (rows = camera channels, columns = LEDs).
codes::Crosstalk parse_crosstalk(const std::string& text);

/// \brief A code argument: a library name or digits. `leds` 0 infers the LED
/// count: a string of 0s and 1s is a one-LED code, anything else a code of the
/// product's 3 LEDs. Throws UsageError naming the argument and slot.
LedCode parse_code_argument(const std::string& argument, int leds, bool require_one_of_n);

/// \brief Merit names (each may be a comma-separated list) to merits; all when empty.
std::vector<codes::Merit> parse_merits(const std::vector<std::string>& names);

}  // namespace flutterscan::app
