#pragma once
// The stability study of issue 7 (`flutterscan bench stability`): for the
// methods joint-wiener, rl and tv and the schemes rect-white, raskar-white,
// seed-maxmin-1 and found-mse, one factor at a time is pushed away from the
// nominal capture (3000 e-, cap 3, read noise 4 e-, 52 px blur along +x, the
// bench camera's crosstalk) and PSNR and barcode decode rate are measured
// over the four barcode scenes with several noise seeds. A method fails where
// its decode rate drops below 90%. Per factor: a CSV, a PSNR chart (failing
// points drawn large) and a decode-rate chart; the report (Markdown) gives
// each curve's threshold and PSNR drop, and the cyclic-shift table of every
// library code.

#include <cstdio>
#include <string>
#include <vector>

namespace flutterscan::bench {

struct StabilityOptions {
  std::string out_dir = "build/bench/stability";  ///< CSV and PNG files go here
  int seeds = 2;                                  ///< noise seeds per scene
  int width = 640, height = 360;                  ///< scene size
  std::vector<std::string> factors;               ///< empty = every factor
  int threads = 2;                                ///< frames simulated and solved at once
  /// The session's per-frame motion refinement, +- this % of the given blur
  /// (0: the methods take the given motion as it is).
  double blur_tolerance_pct = 10;
};

/// \brief The factors' names, in the order they run (--factors takes these).
std::vector<std::string> stability_factor_names();

/// \brief Runs the study, writes its files into options.out_dir (which must
/// exist) and the Markdown report to `report`. Returns an empty string, or
/// what went wrong (an unknown factor, a scene that does not fit, a file
/// that cannot be written).
std::string run_stability_study(const StabilityOptions& options, std::FILE* report);

}  // namespace flutterscan::bench
