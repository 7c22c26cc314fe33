#include "app/code_arguments.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "app/cli_errors.hpp"
#include "codes/library.hpp"

namespace flutterscan::app {
namespace {

std::vector<std::string> split(const std::string& text, char separator) {
  std::vector<std::string> parts;
  std::stringstream stream(text);
  std::string part;
  while (std::getline(stream, part, separator)) parts.push_back(part);
  if (!text.empty() && text.back() == separator) parts.emplace_back();
  return parts;
}

std::string merit_names() {
  std::string names;
  for (codes::Merit merit : codes::kAllMerits) {
    if (!names.empty()) names += ", ";
    names += codes::merit_name(merit);
  }
  return names;
}

void require_finite(double value, const char* flag, bool allow_zero) {
  if (!std::isfinite(value) || value < 0 || (!allow_zero && value == 0))
    throw UsageError(std::string(flag) + " must be a finite number " +
                     (allow_zero ? ">= 0" : "> 0") + ", not " + std::to_string(value));
}

}  // namespace

void add_merit_flags(CLI::App& command, MeritFlags& flags) {
  command
      .add_option("--electrons", flags.electrons,
                  "joint/mse: light level E, e- per channel under rect-white")
      ->capture_default_str();
  command.add_option("--cap", flags.cap, "joint/mse: overdrive cap c (peak <= c E / L per slot)")
      ->capture_default_str();
  command.add_option("--read-noise", flags.read_noise, "joint/mse: read noise, e- rms")
      ->capture_default_str();
  command.add_option("--crosstalk", flags.crosstalk,
                     "joint/mse: LED-to-channel matrix \"m00,m01,m02;m10,...\" (rows = channels)");
  command.add_option("--eps", flags.mse_eps, "mse: regulariser (inverse signal power)")
      ->capture_default_str();
  command.add_option("--pad", flags.single_pad, "single: zero-padded DFT length T")
      ->capture_default_str();
}

codes::Crosstalk parse_crosstalk(const std::string& text) {
  codes::Crosstalk matrix;
  const auto rows = split(text, ';');
  matrix.channels = static_cast<int>(rows.size());
  for (std::size_t r = 0; r < rows.size(); ++r) {
    const auto cells = split(rows[r], ',');
    if (r == 0) matrix.leds = static_cast<int>(cells.size());
    if (static_cast<int>(cells.size()) != matrix.leds)
      throw UsageError("--crosstalk: row " + std::to_string(r) + " has " +
                       std::to_string(cells.size()) + " entries, row 0 has " +
                       std::to_string(matrix.leds));
    for (std::size_t c = 0; c < cells.size(); ++c) {
      std::size_t used = 0;
      double value = 0;
      try {
        value = std::stod(cells[c], &used);
      } catch (const std::exception&) {
        used = 0;
      }
      const bool trailing_space_only = cells[c].find_first_not_of(" \t", used) == std::string::npos;
      if (used == 0 || !trailing_space_only || !std::isfinite(value) || value < 0)
        throw UsageError("--crosstalk: row " + std::to_string(r) + ", column " + std::to_string(c) +
                         ": '" + cells[c] + "' is not a finite non-negative number");
      matrix.gain.push_back(value);
    }
  }
  if (matrix.channels < 1 || matrix.channels > kMaxLeds || matrix.leds < 1 ||
      matrix.leds > kMaxLeds)
    throw UsageError("--crosstalk: the matrix must have 1 to 4 rows and columns");
  return matrix;
}

codes::MeritSettings merit_settings(const MeritFlags& flags) {
  require_finite(flags.electrons, "--electrons", false);
  require_finite(flags.cap, "--cap", false);
  require_finite(flags.read_noise, "--read-noise", true);
  require_finite(flags.mse_eps, "--eps", false);
  if (flags.single_pad < 2 || flags.single_pad > 1 << 20)
    throw UsageError("--pad must be 2 to 1048576, not " + std::to_string(flags.single_pad));
  codes::MeritSettings settings;
  settings.light.electrons = flags.electrons;
  settings.light.cap = flags.cap;
  settings.light.read_noise = flags.read_noise;
  if (!flags.crosstalk.empty()) settings.light.crosstalk = parse_crosstalk(flags.crosstalk);
  settings.mse_eps = flags.mse_eps;
  settings.single_pad = flags.single_pad;
  return settings;
}

LedCode parse_code_argument(const std::string& argument, int leds, bool require_one_of_n) {
  std::string digits = argument;
  if (const auto entry = codes::find_library_code(argument)) {
    digits = std::string(entry->digits);
    if (leds == 0) leds = entry->leds;
  }
  if (leds == 0) {
    // 0s and 1s only: a single flutter code; otherwise the product's three LEDs.
    leds = digits.find_first_not_of("01") == std::string::npos ? 1 : 3;
  }
  const auto code =
      LedCode::parse(digits, leds, require_one_of_n ? CodeRule::kOneOfN : CodeRule::kAnyMask);
  if (!code.ok()) {
    char message[160];
    describe(code.error(), message);
    std::string shown = argument.size() > 70 ? argument.substr(0, 67) + "..." : argument;
    std::string hint;
    if (code.error().error == CodeError::kNoSuchLed && leds < kMaxLeds)
      hint = " (--leds " + std::to_string(leds + 1) + " for a code of more LEDs)";
    throw UsageError("code '" + shown + "': " + message + hint);
  }
  return code.value();
}

std::vector<codes::Merit> parse_merits(const std::vector<std::string>& names) {
  std::vector<codes::Merit> merits;
  for (const auto& list : names)
    for (const auto& name : split(list, ',')) {
      const auto merit = codes::merit_from_name(name);
      if (!merit) throw UsageError("unknown merit '" + name + "': the merits are " + merit_names());
      if (std::find(merits.begin(), merits.end(), *merit) == merits.end()) merits.push_back(*merit);
    }
  if (merits.empty()) merits.assign(codes::kAllMerits.begin(), codes::kAllMerits.end());
  return merits;
}

}  // namespace flutterscan::app
