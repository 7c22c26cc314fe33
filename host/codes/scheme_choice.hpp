#pragma once
// `--scheme auto`: which capture scheme to light a line with, from the
// imaging issue's regime map (docs/algorithms.md, "Where each scheme wins";
// `make bench` part accuracy, build/bench/regime.txt). The map is measured,
// not modelled: for overdrive caps 3 and 8, light levels 30..10000 e- per
// channel and read noise 1..30 e-, the scheme whose best method scored the
// highest PSNR on the label scenes, and the best coded scheme's margin over
// the best white snapshot. The cells below are that run's, copied by hand;
// rerun the bench and update them when the methods change.
//
// A query falls in the nearest cell on log scales of light and read noise;
// caps below 5.5 use the c = 3 map, above it the c = 8 map.

#include <optional>
#include <string>
#include <string_view>

#include "flutterscan/common/led_code.hpp"

namespace flutterscan::codes {

struct SchemeChoice {
  std::string scheme;    ///< "found-mse" or "snapshot-K"
  LedCode code;          ///< its 52-slot pattern, three LEDs (7 = all)
  double margin_db = 0;  ///< best coded minus best snapshot in that cell (> 0: coded wins)
  double cell_electrons = 0, cell_read_noise = 0, cell_cap = 0;  ///< the map cell used
};

/// \brief Slots of a snapshot's exposure: a code's length.
inline constexpr int kSnapshotSlots = 52;

/// \brief The code of the white strobe `name` = "snapshot-K" (K = 1..52): all
/// three LEDs lit for the first K of 52 slots, each at its budget's cap (the
/// regime map's snapshot-K); nothing for any other name.
std::optional<LedCode> snapshot_code(std::string_view name);

/// \brief The scheme that won the regime map's cell nearest to (electrons per
/// channel under rect-white, read noise e-, overdrive cap). Light and read
/// noise must be > 0 and cap >= 1.
SchemeChoice choose_scheme(double electrons, double read_noise, double cap);

}  // namespace flutterscan::codes
