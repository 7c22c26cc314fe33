#pragma once
// Merit functions of LED codes (docs/codes.md). Every merit is computed from
// per-LED spectra sampled on the merit's own frequency grid, so the full
// evaluation (FFT) and the search's incremental evaluation share one formula.

#include <array>
#include <complex>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "flutterscan/common/led_code.hpp"
#include "flutterscan/common/result.hpp"

namespace flutterscan::codes {

enum class Merit { kMaxMin, kAvgMin, kPairs, kSingle, kJoint, kMse };
inline constexpr std::array kAllMerits = {Merit::kMaxMin, Merit::kAvgMin, Merit::kPairs,
                                          Merit::kSingle, Merit::kJoint,  Merit::kMse};

/// \brief The merit's CLI and JSON name ("maxmin", "joint", ...).
std::string_view merit_name(Merit merit);
/// \brief The merit named `name`, if there is one.
std::optional<Merit> merit_from_name(std::string_view name);
/// \brief Unit of the merit's value, for display.
std::string_view merit_unit(Merit merit);
/// \brief False only for mse, where lower is better.
constexpr bool higher_is_better(Merit merit) {
  return merit != Merit::kMse;
}

/// \brief LED-to-channel crosstalk: gain[c * leds + k] is LED k's light in camera channel c.
/// At most kMaxLeds channels.
struct Crosstalk {
  int channels = 0;
  int leds = 0;
  std::vector<double> gain;
};

/// \brief Light budget and camera noise for the joint and mse merits (docs/conventions.md).
struct LightModel {
  double electrons = 3000;  ///< E: e- per channel of a white object under rect-white
  double cap = 3;           ///< c: an LED may run at most c * E / L per slot
  double read_noise = 4;    ///< sigma_r, e- rms
  std::optional<Crosstalk> crosstalk;
};

struct MeritSettings {
  LightModel light;
  double mse_eps = 10;      ///< regulariser of mse: inverse signal power per frequency
  int single_pad = 256;     ///< T: zero-padded DFT length of the single merit (>= L)
  int dense_points = 4096;  ///< dense-grid samples over 0..0.5 for joint and mse
};

/// \brief Why `merit` cannot score `code` under `settings`; empty when it can.
std::string merit_inapplicable(Merit merit, const LedCode& code, const MeritSettings& settings);

/// \brief Per-LED spectra sampled at the frequencies of a grid.
struct GridSpectra {
  int leds = 0;
  int length = 0;                       ///< slots of the code
  std::vector<double> frequency;        ///< cycles per slot
  std::vector<std::complex<double>> h;  ///< h[k * frequency.size() + j]
  std::array<int, kMaxLeds> on_slots{};
  std::span<const std::complex<double>> led(int k) const {
    return {h.data() + static_cast<std::size_t>(k) * frequency.size(), frequency.size()};
  }
};

/// \brief The frequencies `merit` is judged on: the seed grid, the single
/// merit's padded grid, or a dense grid of `dense_points` samples.
std::vector<double> merit_grid(Merit merit, int length, const MeritSettings& settings,
                               int dense_points);

/// \brief Spectra of every LED of `code` on `merit`'s grid, by FFT.
GridSpectra grid_spectra(Merit merit, const LedCode& code, const MeritSettings& settings,
                         int dense_points);

/// \brief The merit computed from spectra on its grid (no refinement). The
/// caller has checked merit_inapplicable.
double merit_on_grid(Merit merit, const GridSpectra& spectra, const MeritSettings& settings);

/// \brief Precomputed per-channel weights of J(w) for given on-slot counts.
class JointWeights {
 public:
  JointWeights(std::span<const int> on_slots, int length, const LightModel& light);
  /// \brief J at one frequency from each LED's spectrum value there.
  double value(std::span<const std::complex<double>> h_at_frequency) const;
  /// \brief I_k: electrons per slot of LED k.
  double intensity(int led) const { return intensity_[static_cast<std::size_t>(led)]; }

 private:
  int leds_;
  int channels_;
  bool diagonal_;  ///< no crosstalk: channel k sees LED k alone
  std::array<double, kMaxLeds * kMaxLeds> amplitude_{};  ///< M[c][k] I_k / sqrt(v_c), by channel
  std::array<double, kMaxLeds> intensity_{};
};

/// \brief The merit on a logarithmic, higher-is-better scale (dB), the
/// objective searches maximise: seed merits as they are, 20 log10(single),
/// 10 log10(joint), -10 log10(mse).
double merit_objective(Merit merit, double value);
/// \brief The inverse of merit_objective.
double merit_from_objective(Merit merit, double objective);

/// \brief A merit's full value: on its grid, refined where the grid is dense.
/// Fails with the reason where the merit does not apply to the code.
Result<double, std::string> evaluate_merit(Merit merit, const LedCode& code,
                                           const MeritSettings& settings);

/// \brief J(f) at one frequency, for plots and refinement.
double joint_information(const LedCode& code, const LightModel& light, double f);

}  // namespace flutterscan::codes
