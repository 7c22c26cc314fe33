#pragma once
// Sums along a linear code's bars (docs/algorithms.md, "Sums along the bars").
// A bar is the same all along its length, and the blur runs along the rows:
// shifting each row along itself commutes with the blur, so the frame's rows
// summed along the bars' slope are a frame of the same code through the same
// PSFs, at (2 h + 1) times the light. Deblurred, they give the code's profile
// with the noise of that much light; what is not a bar (text, a matrix code)
// is smeared along the slope. A model for linear codes only: the session's
// second pass tries it on a window where the frame's own latent read nothing.

#include <vector>

#include "imaging/capture_model.hpp"
#include "imaging/image.hpp"
#include "imaging/metrics.hpp"

namespace flutterscan::imaging {

/// Steepest bar slope looked for (pixels along the rows per row: about 27
/// degrees off the perpendicular to the motion). Bars turned further are
/// closer to the motion, and the blur along them costs them less.
inline constexpr double kMaxBarSlope = 0.5;

/// Largest change of the bars' slope across the box bar_slope() judges it in
/// that it looks for: bars in strong perspective (a label's vanishing point
/// about two of its widths away).
inline constexpr double kMaxSlopeChange = 0.48;

/// \brief The bars' slope (x shift per row) over a window. A label seen in
/// perspective has bars that are not parallel: its bars meet at a vanishing
/// point, and through each point (x, y) passes the bar of slope
/// (at_origin + per_column (x - origin_x)) / (1 + per_column (y - origin_y)),
/// exact for lines through one point; per_column 0: parallel bars.
struct BarSlope {
  double at_origin = 0;   ///< the slope of the bar through the origin
  double per_column = 0;  ///< how much more a bar one column further along the origin's row slopes
  double origin_x = 0;
  double origin_y = 0;
  /// Where bar_slope() judged it: the box round the bars of one code (empty: not judged).
  Region judged_over{};

  /// The slope of the bar through (x, y).
  [[nodiscard]] double at(double x, double y) const;
};

/// \brief The part of `latent` where one code's bars are: the box round the tiles
/// (64 px square) reached from the strongest (each tile's bar strength: the contrast its rows,
/// summed 8 either side, keep along the best of slopes 0.05 apart, less the mean over them) through
/// neighbours (sides and corners) at least a quarter as strong, each sloping
/// within 0.2 of the tile it was reached from (bars in perspective change their
/// slope along the code, a little from tile to tile: on a real Code 128 leaning
/// 0.18 more at one end than the other, neighbours' best slopes 0.05 apart
/// came 0.15 apart; other stripes, another label's bars, slope otherwise).
/// The whole plane where no tile has bars.
Region bar_region(const Plane& latent);

/// \brief The bars' slope in `latent`, judged where one code's bars are: the
/// box round the 64 px tiles whose contrast depends most on the slope their
/// rows are summed along, grown from the strongest through neighbours at least
/// a quarter as strong and sloping within 0.2 of it (docs/algorithms.md;
/// the whole plane where no tile has bars). In the box, its origin the box's
/// centre: the slopes along which the rows, summed `half_rows` either side,
/// keep the most contrast along the rows. Parallel bars first (|slope| <=
/// kMaxBarSlope, 0.05 then 0.01 apart), then bars in perspective about the
/// slope found (the slope's change across the box within +-kMaxSlopeChange,
/// 0.04 then 0.01 apart; the slope at the centre again 0.01 apart between).
BarSlope bar_slope(const Plane& latent, int half_rows);

/// \brief bar_slope() judged in `box`, bar_region() of `latent` found before
/// (the session's second pass judges a window's slope twice, over 16 and 24
/// rows either side, in the one box).
BarSlope bar_slope(const Plane& latent, const Region& box, int half_rows);

/// \brief Which rows of `latent` sum 2 `half_rows` + 1 rows that all cross
/// the bars `slope` found (bar_slope() on `latent`). A row's bars' strength:
/// over the columns the slope was judged on, the contrast its 17 rows keep
/// summed along the slope less what they keep along slopes 0.15 steeper and
/// shallower; row y sums bars where every 17-row sum that covers its rows is at
/// least half the strongest row's. Elsewhere the sums mix the bars with what
/// lies above or below them (the digits under an EAN-13, another code, a
/// label's edge), which a decoder can read as another value that passes the
/// symbology's check. Rows within half_rows of the plane's ends: not.
std::vector<bool> rows_across_bars(const Plane& latent, const BarSlope& slope, int half_rows);

/// \brief Each row of each plane of `electrons` replaced by the sum of the
/// 2 `half_rows` + 1 rows centred on it, along the bars: row k away read at
/// x + k `slope`.at(x, y) (linear interpolation; beyond a row's ends, its end
/// sample). Near the first and last rows, the rows there are summed and scaled
/// to as many.
Image sum_along_bars(const Image& electrons, const BarSlope& slope, int half_rows);

/// \brief The capture model of `rows` rows summed: the light (LEDs and ambient)
/// and full well `rows` times, the read noise and the quantisation's step
/// sqrt(`rows`) times (their variances add).
CaptureModel model_of_row_sums(CaptureModel model, int rows);

}  // namespace flutterscan::imaging
