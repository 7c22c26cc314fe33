#pragma once
// Everything `flutterscan codes score` says about a code: per-LED spectra
// facts and every requested merit, as text for people and JSON for programs.

#include <nlohmann/json.hpp>

#include <optional>
#include <span>
#include <string>
#include <vector>

#include "codes/merits.hpp"
#include "codes/spectrum.hpp"

namespace flutterscan::codes {

struct LedReport {
  int led = 0;
  int on_slots = 0;
  double duty_cycle = 0;
  double seed_grid_min_db = 0;  ///< 64-point grid (seed)
  Minimum dense_min_db;         ///< linear blur: dense grid and refined
  double circular_min_db = 0;   ///< L-point circular DFT
};

struct MeritReport {
  Merit merit;
  std::optional<double> value;  ///< empty where the merit does not apply
  std::string inapplicable;     ///< why not
};

struct CodeReport {
  LedCode code;
  std::string name;  ///< library name, if the code came from the library
  std::vector<LedReport> leds;
  std::vector<MeritReport> merits;
  std::optional<double> joint_ratio_to_best_seed;
  std::string best_seed_triplet;  ///< library name of the seed triplet with the highest joint
};

/// \brief The code's digits as a string.
std::string format_code(const LedCode& code);

/// \brief Computes the report for `merits` under `settings`.
CodeReport make_code_report(const LedCode& code, std::span<const Merit> merits,
                            const MeritSettings& settings);

/// \brief One JSON object: the code, per-LED facts, and every merit by name (null where n/a).
nlohmann::json to_json(const CodeReport& report, const MeritSettings& settings);

/// \brief A few aligned lines for a terminal.
std::string to_text(const CodeReport& report, const MeritSettings& settings);

}  // namespace flutterscan::codes
