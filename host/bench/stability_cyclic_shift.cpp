#include "bench/stability_cyclic_shift.hpp"

#include <cmath>

namespace flutterscan::bench {

LedCode rotate_code(const LedCode& code, int shift) {
  LedCode rotated = code;
  const int length = code.length();
  const int s = ((shift % length) + length) % length;
  for (int t = 0; t < length; ++t) rotated.set_mask(t, code.mask((t + s) % length));
  return rotated;
}

Result<CyclicShiftRobustness, std::string> cyclic_shift_robustness(
    const LedCode& code, codes::Merit merit, const codes::MeritSettings& settings) {
  using Out = Result<CyclicShiftRobustness, std::string>;
  if (auto why = codes::merit_inapplicable(merit, code, settings); !why.empty())
    return Out::failure(why);
  CyclicShiftRobustness r;
  const bool higher = codes::higher_is_better(merit);
  for (int shift = 0; shift < code.length(); ++shift) {
    const auto value = codes::evaluate_merit(merit, rotate_code(code, shift), settings);
    if (!value.ok()) return Out::failure(value.error());
    const double v = value.value();
    r.mean += v / code.length();
    if (shift == 0) {
      r.unshifted = r.worst = v;
      continue;
    }
    if (higher ? v < r.worst : v > r.worst) {
      r.worst = v;
      r.worst_shift = shift;
    }
  }
  return Out::success(r);
}

double cyclic_shift_loss_db(codes::Merit merit, const CyclicShiftRobustness& r) {
  const double objective_loss =
      codes::merit_objective(merit, r.unshifted) - codes::merit_objective(merit, r.worst);
  return std::max(0.0, objective_loss);
}

}  // namespace flutterscan::bench
