#pragma once
// Sums along a linear code's bars (docs/algorithms.md, "Sums along the bars").
// A bar is the same all along its length, and the blur runs along the rows:
// shifting each row along itself commutes with the blur, so the frame's rows
// summed along the bars' slope are a frame of the same code through the same
// PSFs, at (2 h + 1) times the light. Deblurred, they give the code's profile
// with the noise of that much light; what is not a bar (text, a matrix code)
// is smeared along the slope. A model for linear codes only: the session's
// second pass tries it on a window where the frame's own latent read nothing.

#include "imaging/capture_model.hpp"
#include "imaging/image.hpp"

namespace flutterscan::imaging {

/// Steepest bar slope looked for (pixels along the rows per row: about 27
/// degrees off the perpendicular to the motion). Bars turned further are
/// closer to the motion, and the blur along them costs them less.
inline constexpr double kMaxBarSlope = 0.5;

/// \brief The slope (x shift per row, |slope| <= kMaxBarSlope) along which
/// `latent`'s rows, summed `half_rows` either side, keep the most contrast
/// along the rows: the bars' slope where a linear code fills most of it.
/// Slopes 0.05 apart, then 0.01 apart around the best.
double bar_slope(const Plane& latent, int half_rows);

/// \brief Each row of each plane of `electrons` replaced by the sum of the
/// 2 `half_rows` + 1 rows centred on it, row k away shifted by k `slope`
/// pixels along the rows (linear interpolation; beyond a row's ends, its end
/// sample). Near the first and last rows, the rows there are summed and scaled
/// to as many.
Image sum_along_bars(const Image& electrons, double slope, int half_rows);

/// \brief The capture model of `rows` rows summed: the light (LEDs and ambient)
/// and full well `rows` times, the read noise and the quantisation's step
/// sqrt(`rows`) times (their variances add).
CaptureModel model_of_row_sums(CaptureModel model, int rows);

}  // namespace flutterscan::imaging
