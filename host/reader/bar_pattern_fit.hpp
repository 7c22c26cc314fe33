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

}  // namespace flutterscan::reader
