#pragma once
// Line charts rendered to PNG with Cairo, for report figures: power spectra of
// flutter-shutter codes (dB against relative frequency), speed-versus-accuracy
// charts with a log x axis, and the like.
//
// Axis ranges. A bound that is set is used as given. An unset bound is fitted to
// the plottable points (finite x and y, and x > 0 on a log axis) that lie within
// the bounds that are set; y is fitted to the points inside the final x range.
// The fitted range is padded by 3% of its span on each side (in decades on a log
// axis), and a padded end that lies within 5% of the span of a round value
// (a multiple of the span's power of ten, or a decade on a log axis) is moved
// out to it, so that e.g. -78..-3 dB becomes -80..0 dB.
//
// Outliers. When y_min is unset, the fit ignores y values that are both more
// than 80 units below the highest value and below median - 4 * (max - median)
// (median and max of the y values considered). A spectrum peaking at 0 dB with
// a median of -15 dB thus fits to about -80..0 dB instead of stretching to its
// -240 dB nulls, while data that is genuinely spread over a wide range keeps
// all of its values. Ignored values are still drawn: their lines leave through
// the bottom of the plot.
//
// Points that are not plottable break a series' line. Lines and markers are
// clipped to the plot area.
//
// Sizes (line widths, marker radii, fonts) are in pixels of a 1200 x 720 image
// and scale with the image.

#include <optional>
#include <string>
#include <vector>

namespace flutterscan::plot {

/// \brief A colour, each component in 0..1.
struct Rgb {
  double r, g, b;
};

/// \brief One curve of a chart.
struct Series {
  std::string label;         ///< legend text; empty = not in the legend
  std::vector<double> x, y;  ///< same length
  Rgb colour{0, 0, 0};
  double line_width = 1.5;  ///< 0 = no line (markers only)
  bool dashed = false;
  double marker_radius = 0;  ///< > 0 draws a filled circle at each point
};

/// \brief A chart of curves over common axes.
struct LineChart {
  std::string title, x_label, y_label;
  std::vector<Series> series;
  bool log_x = false;
  std::optional<double> x_min, x_max, y_min, y_max;  ///< unset = fitted to the data
  std::vector<std::string> notes;                    ///< small text lines drawn under the title
};

/// \brief Renders `chart` and writes it as a `width` x `height` PNG to `path`.
///
/// The image is written to a temporary file in the same directory and renamed
/// over `path`, so an existing file is never left half-written. Returns an empty
/// string on success, otherwise a message naming `path` and what failed (no
/// series, x and y lengths differing, a bad axis bound, a missing directory, ...).
std::string write_png(const LineChart& chart, const std::string& path, int width = 1200,
                      int height = 720);

}  // namespace flutterscan::plot
