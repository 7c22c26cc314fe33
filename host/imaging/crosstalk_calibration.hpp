#pragma once
// `calibrate crosstalk`: the LED-to-channel matrix M, the LEDs' strengths, the
// black levels and the channels' relative gains from frames of a white target,
// one with every LED off and one per LED lit alone for whole exposures
// (patterns 1111..., 2222..., 4444...).
//
// Each lit frame gives column k of A[c][k] = mean DN of channel c - its black
// level, measured over the centre of the frame (the middle half in each
// direction, where the white target is), as a robust mean (median). The capture
// model's convention splits A into M (each column sums to 1: LED k's light
// shared over the channels) and the LED strengths (column sums), so
// A[c][k] = M[c][k] * strength[k]. The channels' relative gains are A's row
// sums over their mean (a white-balance reading). M's 2-norm condition number
// is how much unmixing amplifies noise; above kPoorSeparationCondition the
// calibration says that separation will be poor.

#include <span>
#include <string>
#include <vector>

#include "flutterscan/common/result.hpp"
#include "imaging/image.hpp"

namespace flutterscan::imaging {

/// \brief Above this condition number of M, unmixing amplifies noise by more than 5x.
inline constexpr double kPoorSeparationCondition = 5.0;

struct CrosstalkCalibration {
  int channels = 0, leds = 0;
  std::vector<double> crosstalk;        ///< M, row-major channels x leds, columns sum to 1
  std::vector<double> led_strength_dn;  ///< column sums of A: DN over all channels per LED
  std::vector<double> black_level_dn;   ///< per channel, from the dark frame
  std::vector<double> channel_gain;     ///< relative: row sums of A over their mean
  double condition_number = 0;          ///< of M (2-norm)
  std::string warning;                  ///< non-empty when separation will be poor
};

/// \brief Calibrates from `dark` (every LED off) and `lit[k]` (LED k alone), all in
/// DN with the same channels and size. Fails naming the frame that is missing,
/// mismatched, saturated in the centre, or too dark to measure.
Result<CrosstalkCalibration, std::string> calibrate_crosstalk(const Image& dark,
                                                              std::span<const Image> lit,
                                                              double full_scale_dn);

/// \brief The 2-norm condition number of a rows x cols matrix (row-major):
/// largest over smallest singular value (infinity if singular).
double condition_number(const std::vector<double>& matrix, int rows, int cols);

}  // namespace flutterscan::imaging
