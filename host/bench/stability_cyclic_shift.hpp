#pragma once
// Which codes stay good under every cyclic shift (issue 7). A rolling-shutter
// row sees the cyclically repeated pattern from its own phase, so a code used
// that way must be good at every rotation, not only at slot 0: its merit
// (joint or mse of host/codes) minimised over all L whole-slot rotations.
// Fractional phases lie between two whole ones (their PSF mixes the two).

#include <string>

#include "codes/merits.hpp"
#include "flutterscan/common/led_code.hpp"
#include "flutterscan/common/result.hpp"

namespace flutterscan::bench {

/// \brief `code` rotated so that slot `shift` comes first: slot t of the result is
/// slot (t + shift) mod L of `code` (the view of a row at phase `shift`).
LedCode rotate_code(const LedCode& code, int shift);

/// \brief A code's merit at its own phase and at its worst rotation.
struct CyclicShiftRobustness {
  double unshifted = 0;  ///< the merit at shift 0
  double worst = 0;      ///< the worst over all L shifts (lowest; highest for mse)
  int worst_shift = 0;
  double mean = 0;  ///< the mean over all L shifts
};

/// \brief Evaluates `merit` at every rotation of `code`. Fails where the merit
/// does not apply to the code.
Result<CyclicShiftRobustness, std::string> cyclic_shift_robustness(
    const LedCode& code, codes::Merit merit, const codes::MeritSettings& settings);

/// \brief The worst shift's loss in dB against shift 0, >= 0: 10 log10 of the
/// ratio for joint and mse (powers), 20 log10 for single, the difference for
/// the seed merits (already in dB).
double cyclic_shift_loss_db(codes::Merit merit, const CyclicShiftRobustness& r);

}  // namespace flutterscan::bench
