#include "plot/line_chart.hpp"

#include "plot/png_file.hpp"

#include <cairo.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>
#include <numbers>

namespace flutterscan::plot {
namespace {

// ---------------------------------------------------------------- validation

std::string series_name(const LineChart& chart, std::size_t index) {
  const std::string& label = chart.series[index].label;
  return "series " + std::to_string(index) + (label.empty() ? "" : " (\"" + label + "\")");
}

/// The first problem that keeps `chart` from being drawn, or an empty string.
std::string check_chart(const LineChart& chart, int width, int height) {
  if (width < 320 || height < 200 || width > 16384 || height > 16384) {
    return "image size " + std::to_string(width) + " x " + std::to_string(height) +
           " is outside 320 x 200 .. 16384 x 16384";
  }
  if (chart.series.empty()) return "the chart has no series";
  for (std::size_t i = 0; i < chart.series.size(); ++i) {
    const Series& series = chart.series[i];
    if (series.x.size() != series.y.size()) {
      return series_name(chart, i) + " has " + std::to_string(series.x.size()) + " x values but " +
             std::to_string(series.y.size()) + " y values";
    }
    if (!std::isfinite(series.line_width) || series.line_width < 0 ||
        !std::isfinite(series.marker_radius) || series.marker_radius < 0) {
      return series_name(chart, i) + " has a negative or non-finite line width or marker radius";
    }
  }
  for (const auto& bound : {chart.x_min, chart.x_max, chart.y_min, chart.y_max}) {
    if (bound && !std::isfinite(*bound)) return "an axis bound is not finite";
  }
  if (chart.log_x && ((chart.x_min && *chart.x_min <= 0) || (chart.x_max && *chart.x_max <= 0))) {
    return "a log x axis needs positive bounds";
  }
  if (chart.x_min && chart.x_max && *chart.x_min >= *chart.x_max) return "x_min is not below x_max";
  if (chart.y_min && chart.y_max && *chart.y_min >= *chart.y_max) return "y_min is not below y_max";
  return {};
}

// ---------------------------------------------------------------- axis ranges

constexpr double kPadFraction = 0.03;
constexpr double kSnapFraction = 0.05;
constexpr double kOutlierDepth = 80.0;
constexpr double kOutlierSpread = 4.0;

/// A visible range in axis space: the value, or its log10 on a log axis.
struct Range {
  double lo, hi;
};

double to_axis(double value, bool log) {
  return log ? std::log10(value) : value;
}

bool plottable(double x, double y, bool log_x) {
  return std::isfinite(x) && std::isfinite(y) && (!log_x || x > 0);
}

bool within(double value, std::optional<double> lo, std::optional<double> hi) {
  return (!lo || value >= *lo) && (!hi || value <= *hi);
}

std::optional<Range> extent(const std::vector<double>& values) {
  if (values.empty()) return std::nullopt;
  const auto [lo, hi] = std::minmax_element(values.begin(), values.end());
  return Range{*lo, *hi};
}

/// Drops the y values the fit ignores as outliers (see the header).
std::vector<double> without_outliers(std::vector<double> ys) {
  if (ys.empty()) return ys;
  std::sort(ys.begin(), ys.end());
  const double max = ys.back();
  const double median = ys[ys.size() / 2];
  const double floor = std::min(max - kOutlierDepth, median - kOutlierSpread * (max - median));
  std::erase_if(ys, [floor](double y) { return y < floor; });
  return ys;
}

/// `value` moved down (direction -1) or up (+1) to a multiple of `unit` if that is within `reach`.
double snap_out(double value, double unit, double reach, int direction) {
  const double round =
      direction < 0 ? std::floor(value / unit) * unit : std::ceil(value / unit) * unit;
  return std::abs(round - value) <= reach ? round : value;
}

/// The range shown on an axis, given its set bounds and the extent of its data (axis space).
Range fit_range(std::optional<double> set_lo, std::optional<double> set_hi,
                std::optional<Range> data, bool log) {
  if (set_lo && set_hi) return {*set_lo, *set_hi};
  Range range = data.value_or(Range{0.0, 1.0});
  if (set_lo) range.lo = *set_lo;
  if (set_hi) range.hi = *set_hi;
  if (range.hi <= range.lo) {
    const double centre = set_lo ? range.lo : range.hi;
    const double span = (log || centre == 0) ? 1.0 : 0.2 * std::abs(centre);
    if (set_lo) {
      range.hi = range.lo + span;
    } else if (set_hi) {
      range.lo = range.hi - span;
    } else {
      range = {centre - span / 2, centre + span / 2};
    }
  }
  const double span = range.hi - range.lo;
  const double unit = log ? 1.0 : std::pow(10.0, std::floor(std::log10(span)));
  if (!set_lo) range.lo = snap_out(range.lo - kPadFraction * span, unit, kSnapFraction * span, -1);
  if (!set_hi) range.hi = snap_out(range.hi + kPadFraction * span, unit, kSnapFraction * span, +1);
  return range;
}

Range fit_x(const LineChart& chart) {
  std::vector<double> xs;
  for (const Series& series : chart.series) {
    for (std::size_t i = 0; i < series.x.size(); ++i) {
      const double x = series.x[i];
      if (plottable(x, series.y[i], chart.log_x) && within(x, chart.x_min, chart.x_max)) {
        xs.push_back(to_axis(x, chart.log_x));
      }
    }
  }
  const auto to = [&](std::optional<double> v) {
    return v ? std::optional(to_axis(*v, chart.log_x)) : std::nullopt;
  };
  return fit_range(to(chart.x_min), to(chart.x_max), extent(xs), chart.log_x);
}

Range fit_y(const LineChart& chart, Range x_range) {
  std::vector<double> ys;
  for (const Series& series : chart.series) {
    for (std::size_t i = 0; i < series.x.size(); ++i) {
      const double x = series.x[i];
      const double y = series.y[i];
      if (!plottable(x, y, chart.log_x) || !within(y, chart.y_min, chart.y_max)) continue;
      const double t = to_axis(x, chart.log_x);
      if (t >= x_range.lo && t <= x_range.hi) ys.push_back(y);
    }
  }
  if (!chart.y_min) ys = without_outliers(std::move(ys));
  return fit_range(chart.y_min, chart.y_max, extent(ys), false);
}

// ---------------------------------------------------------------- ticks

struct Tick {
  double value;  ///< data space
  std::string label;
  std::string exponent = {};  ///< drawn as a superscript after the label when not empty
};

struct AxisTicks {
  std::vector<Tick> major;
  std::vector<double> minor;  ///< grid lines without labels, data space
};

/// The smallest of 1, 2, 5 times a power of ten that is at least `raw`.
double nice_step(double raw) {
  const double decade = std::pow(10.0, std::floor(std::log10(raw)));
  for (const double m : {1.0, 2.0, 5.0}) {
    if (m * decade >= raw * (1 - 1e-9)) return m * decade;
  }
  return 10 * decade;
}

/// Typographic minus signs and exponents without '+' or leading zeros ("1e−6").
std::string tidy_number(const char* text) {
  std::string out;
  for (const char* c = text; *c != '\0'; ++c) {
    if (*c == '-') {
      out += "\u2212";
    } else if (*c == 'e') {
      const int exponent = std::atoi(c + 1);
      out += 'e';
      if (exponent < 0) out += "\u2212";
      out += std::to_string(std::abs(exponent));
      break;
    } else {
      out += *c;
    }
  }
  return out;
}

/// `value` printed with as many decimals as a tick `step` needs.
std::string step_label(double value, double step) {
  if (std::abs(value) < step * 1e-6) value = 0;
  char text[48];
  if (std::max(std::abs(value), step) >= 1e6 || step < 1e-5) {
    std::snprintf(text, sizeof text, "%g", value);
  } else {
    const int decimals = std::max(0, -static_cast<int>(std::floor(std::log10(step) + 1e-9)));
    std::snprintf(text, sizeof text, "%.*f", decimals, value);
  }
  return tidy_number(text);
}

/// The log-axis tick at `mantissa` x 10^`exponent`: written out ("0.002", "500"), or
/// as a power of ten ("2×10" with superscript "6") when `powers`.
Tick decade_tick(int mantissa, int exponent, bool powers) {
  const double value = mantissa * std::pow(10.0, exponent);
  if (powers) {
    return {value, mantissa == 1 ? "10" : std::to_string(mantissa) + "\u00d710",
            tidy_number(std::to_string(exponent).c_str())};
  }
  char text[48];
  std::snprintf(text, sizeof text, "%.*f", std::max(0, -exponent), value);
  return {value, text};
}

/// Ticks at multiples of a 1-2-5 step, at most `max_count` of them, over values lo..hi.
std::vector<Tick> linear_ticks(double lo, double hi, int max_count) {
  const double step = nice_step((hi - lo) / max_count);
  std::vector<Tick> ticks;
  const double first = std::ceil(lo / step - 1e-9);
  const double last = std::floor(hi / step + 1e-9);
  for (double k = first; k <= last; ++k) ticks.push_back({k * step, step_label(k * step, step)});
  return ticks;
}

/// Log-axis ticks: 1, 2 and 5 per decade when they fit, else decades (every n-th when
/// there are many), else 1-2-5 steps of the value when the range is under a decade.
AxisTicks log_ticks(Range range, int max_count) {
  constexpr double kEps = 1e-9;
  // Values are written out when all labels would lie within 0.001..500000.
  const bool powers = std::floor(range.lo + kEps) < -3 || std::floor(range.hi + kEps) > 5;
  AxisTicks one_two_five;
  std::vector<int> decades;
  std::vector<double> between_decades;  // m x 10^k for m = 2..9
  for (int k = static_cast<int>(std::floor(range.lo)); k <= static_cast<int>(std::ceil(range.hi));
       ++k) {
    for (int m = 1; m <= 9; ++m) {
      const double t = k + std::log10(m);
      if (t < range.lo - kEps || t > range.hi + kEps) continue;
      const Tick tick = decade_tick(m, k, powers);
      if (m == 1) {
        decades.push_back(k);
      } else {
        between_decades.push_back(tick.value);
      }
      if (m == 1 || m == 2 || m == 5) {
        one_two_five.major.push_back(tick);
      } else {
        one_two_five.minor.push_back(tick.value);
      }
    }
  }
  const auto count = static_cast<int>(one_two_five.major.size());
  if (count >= 3 && count <= max_count) return one_two_five;
  if (decades.size() >= 2) {
    AxisTicks ticks;
    const int stride = (static_cast<int>(decades.size()) + max_count - 1) / max_count;
    for (const int k : decades) {
      if (k % stride == 0) {
        ticks.major.push_back(decade_tick(1, k, powers));
      } else {
        ticks.minor.push_back(std::pow(10.0, k));
      }
    }
    if (stride == 1) ticks.minor = between_decades;
    return ticks;
  }
  return {linear_ticks(std::pow(10.0, range.lo), std::pow(10.0, range.hi), max_count), {}};
}

// ---------------------------------------------------------------- drawing

/// Font sizes at the 1200 x 720 reference size.
constexpr double kTitleFont = 26;
constexpr double kNoteFont = 17;
constexpr double kLabelFont = 21;
constexpr double kTickFont = 18;
constexpr double kLegendFont = 18;

struct Point {
  double x, y;
};

struct Box {
  double left, top, right, bottom;
};

/// Maps an axis's data values to device pixels.
struct AxisMap {
  Range range;
  bool log;
  double px_lo, px_hi;  ///< pixels of range.lo and range.hi

  double operator()(double value) const {
    return px_lo + (to_axis(value, log) - range.lo) / (range.hi - range.lo) * (px_hi - px_lo);
  }
};

void set_font(cairo_t* cr, double size, bool bold = false) {
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL,
                         bold ? CAIRO_FONT_WEIGHT_BOLD : CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, size);
}

double text_width(cairo_t* cr, const std::string& text) {
  cairo_text_extents_t extents;
  cairo_text_extents(cr, text.c_str(), &extents);
  return extents.x_advance;
}

double cap_height(cairo_t* cr) {
  cairo_text_extents_t extents;
  cairo_text_extents(cr, "H", &extents);
  return extents.height;
}

/// Draws `text` with (x, y) at fraction (ax, ay) of its box: ax across the advance
/// width, ay from the top of capitals (0) to the baseline (1).
void draw_text(cairo_t* cr, const std::string& text, double x, double y, double ax, double ay) {
  cairo_move_to(cr, x - ax * text_width(cr, text), y + (1 - ay) * cap_height(cr));
  cairo_show_text(cr, text.c_str());
}

/// Size of a tick label's exponent relative to its font.
constexpr double kSuperscript = 0.7;

double tick_width(cairo_t* cr, const Tick& tick) {
  double width = text_width(cr, tick.label);
  if (!tick.exponent.empty()) {
    cairo_matrix_t font;
    cairo_get_font_matrix(cr, &font);
    cairo_set_font_size(cr, kSuperscript * font.xx);
    width += text_width(cr, tick.exponent);
    cairo_set_font_matrix(cr, &font);
  }
  return width;
}

/// Draws a tick label like draw_text, its exponent raised after it.
void draw_tick(cairo_t* cr, const Tick& tick, double x, double y, double ax, double ay) {
  const double left = x - ax * tick_width(cr, tick);
  draw_text(cr, tick.label, left, y, 0, ay);
  if (tick.exponent.empty()) return;
  const double cap = cap_height(cr);
  cairo_move_to(cr, left + text_width(cr, tick.label) + 0.05 * cap, y + (0.45 - ay) * cap);
  cairo_matrix_t font;
  cairo_get_font_matrix(cr, &font);
  cairo_set_font_size(cr, kSuperscript * font.xx);
  cairo_show_text(cr, tick.exponent.c_str());
  cairo_set_font_matrix(cr, &font);
}

/// The device coordinate of the middle of the pixel nearest `v`, for crisp 1-pixel lines.
double crisp(double v) {
  return std::round(v - 0.5) + 0.5;
}

/// Chooses ticks for an axis `length` pixels long whose labels fit their spacing:
/// `label_extent` gives a tick label's size along the axis.
template <typename LabelExtent>
AxisTicks fitting_ticks(Range range, bool log, double length, double per_tick,
                        LabelExtent label_extent) {
  for (int max_count = std::max(2, static_cast<int>(length / per_tick));; --max_count) {
    AxisTicks ticks = log ? log_ticks(range, max_count)
                          : AxisTicks{linear_ticks(range.lo, range.hi, max_count), {}};
    const AxisMap map{range, log, 0, length};
    bool fits = true;
    for (std::size_t i = 1; i < ticks.major.size(); ++i) {
      const double gap = std::abs(map(ticks.major[i].value) - map(ticks.major[i - 1].value));
      const double need = (label_extent(ticks.major[i]) + label_extent(ticks.major[i - 1])) / 2;
      fits = fits && gap >= need * 1.25;
    }
    if (fits || max_count <= 2) return ticks;
  }
}

void set_series_stroke(cairo_t* cr, const Series& series, double scale) {
  const double width = series.line_width * scale;
  cairo_set_source_rgb(cr, series.colour.r, series.colour.g, series.colour.b);
  cairo_set_line_width(cr, width);
  cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
  if (series.dashed) {
    const double dashes[] = {3.5 * width + 4 * scale, 2 * width + 3 * scale};
    cairo_set_dash(cr, dashes, 2, 0);
    cairo_set_line_cap(cr, CAIRO_LINE_CAP_BUTT);
  } else {
    cairo_set_dash(cr, nullptr, 0, 0);
    cairo_set_line_cap(cr, CAIRO_LINE_CAP_ROUND);
  }
}

struct ClippedSegment {
  Point a, b;
  bool a_moved, b_moved;
};

/// The part of segment a-b inside `box` (Liang-Barsky), if any.
std::optional<ClippedSegment> clip_segment(Point a, Point b, const Box& box) {
  const double dx = b.x - a.x;
  const double dy = b.y - a.y;
  if (!std::isfinite(dx) || !std::isfinite(dy)) return std::nullopt;
  double t0 = 0;
  double t1 = 1;
  // Keeps the part where p * t <= q.
  const auto keep = [&](double p, double q) {
    if (p == 0) return q >= 0;
    const double t = q / p;
    if (p < 0) {
      t0 = std::max(t0, t);
    } else {
      t1 = std::min(t1, t);
    }
    return t0 <= t1;
  };
  if (!keep(-dx, a.x - box.left) || !keep(dx, box.right - a.x) || !keep(-dy, a.y - box.top) ||
      !keep(dy, box.bottom - a.y)) {
    return std::nullopt;
  }
  return ClippedSegment{
      {a.x + t0 * dx, a.y + t0 * dy}, {a.x + t1 * dx, a.y + t1 * dy}, t0 > 0, t1 < 1};
}

/// Draws one series' line and markers; the caller clips to the plot area.
void draw_series(cairo_t* cr, const Series& series, bool log_x, const AxisMap& x_map,
                 const AxisMap& y_map, const Box& plot, double scale) {
  std::vector<std::optional<Point>> points(series.x.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!plottable(series.x[i], series.y[i], log_x)) continue;
    const Point p{x_map(series.x[i]), y_map(series.y[i])};
    if (std::isfinite(p.x) && std::isfinite(p.y)) points[i] = p;
  }
  set_series_stroke(cr, series, scale);
  if (series.line_width > 0) {
    const double reach = series.line_width * scale + 2;
    const Box bounds{plot.left - reach, plot.top - reach, plot.right + reach, plot.bottom + reach};
    bool open = false;  // the path ends at the previous point
    for (std::size_t i = 1; i < points.size(); ++i) {
      const auto segment = points[i - 1] && points[i]
                               ? clip_segment(*points[i - 1], *points[i], bounds)
                               : std::nullopt;
      if (!segment) {
        open = false;
        continue;
      }
      if (!open || segment->a_moved) cairo_move_to(cr, segment->a.x, segment->a.y);
      cairo_line_to(cr, segment->b.x, segment->b.y);
      open = !segment->b_moved;
    }
    cairo_stroke(cr);
  }
  if (series.marker_radius > 0) {
    const double radius = series.marker_radius * scale;
    for (const auto& p : points) {
      if (!p || p->x < plot.left - radius || p->x > plot.right + radius ||
          p->y < plot.top - radius || p->y > plot.bottom + radius) {
        continue;
      }
      cairo_new_sub_path(cr);
      cairo_arc(cr, p->x, p->y, radius, 0, 2 * std::numbers::pi);
    }
    cairo_fill(cr);
  }
}

void draw_legend(cairo_t* cr, const LineChart& chart, const Box& plot, double scale) {
  std::vector<const Series*> entries;
  for (const Series& series : chart.series) {
    if (!series.label.empty()) entries.push_back(&series);
  }
  if (entries.empty()) return;
  set_font(cr, kLegendFont * scale);
  const double inset = 12 * scale;
  const double padding = 10 * scale;
  const double sample = 42 * scale;
  const double gap = 10 * scale;
  const double row = 1.5 * kLegendFont * scale;
  double text = 0;
  for (const Series* series : entries) text = std::max(text, text_width(cr, series->label));
  const double width = 2 * padding + sample + gap + text;
  const double height = 2 * padding + row * static_cast<double>(entries.size()) - 0.3 * row;
  const double left = std::round(plot.right - inset - width);
  const double top = std::round(plot.top + inset);

  cairo_rectangle(cr, left + 0.5, top + 0.5, std::round(width), std::round(height));
  cairo_set_source_rgba(cr, 1, 1, 1, 0.85);
  cairo_fill_preserve(cr);
  cairo_set_source_rgb(cr, 0.7, 0.7, 0.7);
  cairo_set_line_width(cr, 1);
  cairo_set_dash(cr, nullptr, 0, 0);
  cairo_stroke(cr);

  for (std::size_t i = 0; i < entries.size(); ++i) {
    const Series& series = *entries[i];
    const double y = top + padding + 0.35 * row + row * static_cast<double>(i);
    const double x = left + padding;
    set_series_stroke(cr, series, scale);
    if (series.line_width > 0) {
      cairo_move_to(cr, x, y);
      cairo_line_to(cr, x + sample, y);
      cairo_stroke(cr);
    }
    if (series.marker_radius > 0) {
      const double radius = std::min(series.marker_radius * scale, 0.3 * row);
      cairo_arc(cr, x + sample / 2, y, radius, 0, 2 * std::numbers::pi);
      cairo_fill(cr);
    }
    cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
    draw_text(cr, series.label, x + sample + gap, y, 0, 0.5);
  }
}

void draw_grid(cairo_t* cr, const AxisTicks& x_ticks, const AxisTicks& y_ticks,
               const AxisMap& x_map, const AxisMap& y_map, const Box& plot) {
  const auto lines = [&](const std::vector<double>& xs, const std::vector<double>& ys) {
    for (const double x : xs) {
      cairo_move_to(cr, crisp(x_map(x)), plot.top);
      cairo_line_to(cr, crisp(x_map(x)), plot.bottom);
    }
    for (const double y : ys) {
      cairo_move_to(cr, plot.left, crisp(y_map(y)));
      cairo_line_to(cr, plot.right, crisp(y_map(y)));
    }
    cairo_stroke(cr);
  };
  const auto values = [](const std::vector<Tick>& ticks) {
    std::vector<double> out;
    for (const Tick& tick : ticks) out.push_back(tick.value);
    return out;
  };
  cairo_set_line_width(cr, 1);
  cairo_set_source_rgb(cr, 0.93, 0.93, 0.93);
  lines(x_ticks.minor, y_ticks.minor);
  cairo_set_source_rgb(cr, 0.84, 0.84, 0.84);
  lines(values(x_ticks.major), values(y_ticks.major));
}

/// Draws the whole chart onto a `width` x `height` surface.
void draw_chart(cairo_t* cr, const LineChart& chart, int width, int height) {
  const double scale = std::max(0.45, std::min(width / 1200.0, height / 720.0));
  const double pad = 16 * scale;
  const double tick_length = 6 * scale;
  const double tick_gap = 6 * scale;

  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_paint(cr);

  // Vertical layout: title and notes above the plot, tick labels and x label below.
  double top = pad;
  if (!chart.title.empty()) {
    set_font(cr, kTitleFont * scale, true);
    top += cap_height(cr) + 0.55 * kTitleFont * scale;
  }
  set_font(cr, kNoteFont * scale);
  const double note_cap = cap_height(cr);
  const double note_pitch = 1.35 * kNoteFont * scale;
  top += note_pitch * static_cast<double>(chart.notes.size());
  top = std::round(top + 14 * scale);

  set_font(cr, kTickFont * scale);
  const double tick_cap = cap_height(cr);
  const double x_label_space = chart.x_label.empty() ? 0 : 1.3 * kLabelFont * scale + 8 * scale;
  const double bottom =
      std::round(height - pad - x_label_space - tick_cap - tick_gap - tick_length);

  const Range x_range = fit_x(chart);
  const Range y_range = fit_y(chart, x_range);
  const AxisTicks y_ticks = fitting_ticks(y_range, false, bottom - top, 55 * scale,
                                          [tick_cap](const Tick&) { return 1.4 * tick_cap; });
  double y_tick_width = 0;
  for (const Tick& tick : y_ticks.major) {
    y_tick_width = std::max(y_tick_width, tick_width(cr, tick));
  }
  const double y_label_space = chart.y_label.empty() ? 0 : 1.3 * kLabelFont * scale + 6 * scale;
  const Box plot{std::round(pad + y_label_space + y_tick_width + tick_gap + tick_length), top,
                 std::round(width - 2.2 * pad), bottom};
  const AxisMap x_map{x_range, chart.log_x, plot.left, plot.right};
  const AxisMap y_map{y_range, false, plot.bottom, plot.top};
  const AxisTicks x_ticks = fitting_ticks(x_range, chart.log_x, plot.right - plot.left, 110 * scale,
                                          [cr](const Tick& tick) { return tick_width(cr, tick); });

  draw_grid(cr, x_ticks, y_ticks, x_map, y_map, plot);

  cairo_save(cr);
  cairo_rectangle(cr, plot.left, plot.top, plot.right - plot.left, plot.bottom - plot.top);
  cairo_clip(cr);
  for (const Series& series : chart.series) {
    draw_series(cr, series, chart.log_x, x_map, y_map, plot, scale);
  }
  cairo_restore(cr);

  // Frame, ticks and tick labels.
  const double frame = std::max(1.0, std::round(1.2 * scale));
  const double edge = std::fmod(frame, 2.0) == 1.0 ? 0.5 : 0.0;
  cairo_set_dash(cr, nullptr, 0, 0);
  cairo_set_line_cap(cr, CAIRO_LINE_CAP_SQUARE);
  cairo_set_line_width(cr, frame);
  cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
  cairo_rectangle(cr, plot.left + edge, plot.top + edge, plot.right - plot.left - 2 * edge,
                  plot.bottom - plot.top - 2 * edge);
  for (const Tick& tick : x_ticks.major) {
    cairo_move_to(cr, crisp(x_map(tick.value)), plot.bottom);
    cairo_line_to(cr, crisp(x_map(tick.value)), plot.bottom + tick_length);
  }
  for (const Tick& tick : y_ticks.major) {
    cairo_move_to(cr, plot.left, crisp(y_map(tick.value)));
    cairo_line_to(cr, plot.left - tick_length, crisp(y_map(tick.value)));
  }
  cairo_stroke(cr);
  cairo_set_source_rgb(cr, 0.15, 0.15, 0.15);
  for (const Tick& tick : x_ticks.major) {
    draw_tick(cr, tick, x_map(tick.value), plot.bottom + tick_length + tick_gap, 0.5, 0);
  }
  for (const Tick& tick : y_ticks.major) {
    draw_tick(cr, tick, plot.left - tick_length - tick_gap, y_map(tick.value), 1, 0.5);
  }

  // Axis labels, title and notes.
  set_font(cr, kLabelFont * scale);
  cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
  if (!chart.x_label.empty()) {
    draw_text(cr, chart.x_label, (plot.left + plot.right) / 2,
              height - pad - 0.3 * kLabelFont * scale, 0.5, 1);
  }
  if (!chart.y_label.empty()) {
    cairo_save(cr);
    cairo_translate(cr, pad, (plot.top + plot.bottom) / 2);
    cairo_rotate(cr, -std::numbers::pi / 2);
    draw_text(cr, chart.y_label, 0, 0, 0.5, 0);
    cairo_restore(cr);
  }
  const double centre = (plot.left + plot.right) / 2;
  double line_top = pad;
  if (!chart.title.empty()) {
    set_font(cr, kTitleFont * scale, true);
    cairo_set_source_rgb(cr, 0, 0, 0);
    draw_text(cr, chart.title, centre, line_top, 0.5, 0);
    line_top += cap_height(cr) + 0.55 * kTitleFont * scale;
  }
  set_font(cr, kNoteFont * scale);
  cairo_set_source_rgb(cr, 0.35, 0.35, 0.35);
  for (const std::string& note : chart.notes) {
    draw_text(cr, note, centre, line_top + (note_pitch - note_cap) / 2, 0.5, 0);
    line_top += note_pitch;
  }

  draw_legend(cr, chart, plot, scale);
}

}  // namespace

std::string write_png(const LineChart& chart, const std::string& path, int width, int height) {
  const auto failed = [&path](const std::string& what) {
    return "cannot write chart '" + path + "': " + what;
  };
  if (const std::string problem = check_chart(chart, width, height); !problem.empty()) {
    return failed(problem);
  }
  const std::unique_ptr<cairo_surface_t, decltype(&cairo_surface_destroy)> surface(
      cairo_image_surface_create(CAIRO_FORMAT_RGB24, width, height), cairo_surface_destroy);
  const std::unique_ptr<cairo_t, decltype(&cairo_destroy)> cr(cairo_create(surface.get()),
                                                              cairo_destroy);
  draw_chart(cr.get(), chart, width, height);
  cairo_surface_flush(surface.get());
  if (const cairo_status_t status = cairo_status(cr.get()); status != CAIRO_STATUS_SUCCESS) {
    return failed(std::string("drawing failed: ") + cairo_status_to_string(status));
  }
  if (const std::string problem = write_surface_png(surface.get(), path); !problem.empty()) {
    return failed(problem);
  }
  return {};
}

}  // namespace flutterscan::plot
