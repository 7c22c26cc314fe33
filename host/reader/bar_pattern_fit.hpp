#pragma once
// A read checked against the picture (docs/algorithms.md, "A read's bars
// fitted"). A decoder that reads a linear code through noise can read a value
// that passes the symbology's check digit and is not the label's: tv's flat
// steps on a noisy profile make one module wider, one space narrower, and an
// EAN-13 has only a mod-10 check. The read value says exactly which modules
// are bars: its pattern (ZXing's writer), blurred by a Gaussian and fitted
// (the paper's and the bars' levels, each linear along the code; its ends,
// bend and blur) to a latent where the code lies, must explain
// each of its characters better than any other character the symbology allows
// in that place would. A true read does; a misread has characters the latent
// shows to be others.

#include <string>
#include <vector>

#include "imaging/image.hpp"
#include "reader/barcode_reader.hpp"

namespace flutterscan::reader {

/// \brief What fit_bar_pattern() found.
struct BarPatternFit {
  bool judged = false;  ///< false: see `problem`
  std::string problem;  ///< why not judged: a format it does not know, the code off the latent, ...
  int characters = 0;   ///< the symbol characters compared (an EAN-13's 12)
  /// The character (0-based, left to right in reading order) whose read pattern
  /// the latent supports least against the other characters allowed there, and
  /// that margin: the best other's squared residual less the read one's, over
  /// the fit's noise variance per sample (negative: another fits better).
  int worst_character = -1;
  double worst_margin = 0;
  double contrast =
      0;  ///< the fitted bars' depth below the paper at the code's middle, latent units
  double blur_px = 0;  ///< the fitted Gaussian blur (sigma, px)
};

/// \brief Fits the bars of EAN-13, UPC-A or EAN-8 code `code` (its value and
/// corners, read on another latent of the same place) to `latent` along the
/// code's centre line, and compares each symbol character with the others the
/// symbology allows there (an EAN-13's left half: both parities). Other
/// formats, and codes whose line runs off `latent`, come back not judged.
BarPatternFit fit_bar_pattern(const imaging::Plane& latent, const DecodedCode& code);

/// \brief What read_ean13_by_fit() read.
struct FittedRead {
  std::string text;     ///< the 13 digits; empty: nothing read (see `problem`)
  std::string problem;  ///< why nothing was read
  /// The first bar's leading edge and the last bar's trailing edge, px along
  /// the profile (sample index), in reading order: begin > end where the code
  /// reads right to left along the profile.
  double begin = 0, end = 0;
  int worst_character = -1;  ///< as BarPatternFit's, for the value read
  double worst_margin = 0;
};

/// \brief The least margin a value read_ean13_by_fit() reads must keep at
/// every character (noise variances; a character it chose fits at least as
/// well as every other, so its margin is never negative: on noise alone the
/// best and the second best lie close).
inline constexpr double kMinFittedReadMargin = 6;

/// \brief Reads an EAN-13 from `profile` (one sample per px along a line
/// across its bars) between samples `from` and `to` by fitting the symbol
/// itself rather than thresholding the profile. Where it may lie: the first
/// bar's edge and module width (1.2 to 6 px) whose guards and quiet zones
/// stand out most (the three best places). At each: the ends searched within
/// 6 px, either way round, each character the one of the 20 (left half) or
/// 10 (right half) that fits best, the levels, bend and blur fitted as
/// fit_bar_pattern() fits them, in turn until they settle. A value counts if
/// its parities name a first digit, its check digit holds and every character
/// keeps kMinFittedReadMargin.
FittedRead read_ean13_by_fit(const std::vector<double>& profile, double from, double to);

}  // namespace flutterscan::reader
