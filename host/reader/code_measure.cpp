#include "reader/code_measure.hpp"

#include "imaging/bilinear.hpp"
#include "reader/ean_upc_layout.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <optional>
#include <utility>
#include <vector>

namespace flutterscan::reader {

namespace {

CodePoint operator+(CodePoint a, CodePoint b) {
  return {a.x + b.x, a.y + b.y};
}
CodePoint operator-(CodePoint a, CodePoint b) {
  return {a.x - b.x, a.y - b.y};
}
CodePoint operator*(double s, CodePoint a) {
  return {s * a.x, s * a.y};
}
double length(CodePoint a) {
  return std::hypot(a.x, a.y);
}
CodePoint midpoint(CodePoint a, CodePoint b) {
  return 0.5 * (a + b);
}

/// The reflectance at `p` (imaging::bilinear, clamped to [0, 1]: a deblurred
/// latent's overshoot is no reflectance ISO/IEC 15416 grades); nullopt off the image.
std::optional<double> sample(const imaging::Plane& latent, CodePoint p) {
  const auto v = imaging::bilinear(latent, p.x, p.y);
  if (!v) return std::nullopt;
  return std::clamp(*v, 0.0, 1.0);
}

/// ISO/IEC 15416's grade thresholds (4 = A ... 0 = F) for a parameter that is
/// better higher (`at_least`) or lower (`at_most`), given the A, B, C and D limits.
double grade_at_least(double v, double a, double b, double c, double d) {
  return v >= a ? 4 : v >= b ? 3 : v >= c ? 2 : v >= d ? 1 : 0;
}
double grade_at_most(double v, double a, double b, double c, double d) {
  return v <= a ? 4 : v <= b ? 3 : v <= c ? 2 : v <= d ? 1 : 0;
}
double contrast_grade(double sc) {
  return grade_at_least(sc, 0.70, 0.55, 0.40, 0.20);
}

// ---- linear codes --------------------------------------------------------

/// The scan line of a linear code: reflectance along `axis` through `origin`,
/// t from t0 in steps of `step` px.
struct ScanLine {
  CodePoint origin;
  CodePoint axis;    ///< unit, along the code (left to right)
  CodePoint across;  ///< unit, along the bars (top to bottom)
};

/// Samples of the line at offset `s` across, t in [t0, t1] every `step`; stops
/// short (fewer samples) where the line leaves the image.
std::vector<double> profile(const imaging::Plane& latent, const ScanLine& line, double s, double t0,
                            double t1, double step) {
  std::vector<double> out;
  for (double t = t0; t <= t1 + 1e-9; t += step) {
    const auto v = sample(latent, line.origin + t * line.axis + s * line.across);
    if (!v) break;
    out.push_back(*v);
  }
  return out;
}

/// Where a profile (samples every `step` from `t0`) crosses `threshold`
/// between samples i - 1 and i, linearly interpolated.
double crossing(const std::vector<double>& p, std::size_t i, double threshold, double t0,
                double step) {
  const double a = p[i - 1], b = p[i];
  const double f = a == b ? 0.5 : (threshold - a) / (b - a);
  return t0 + (static_cast<double>(i - 1) + std::clamp(f, 0.0, 1.0)) * step;
}

/// One element of a scan reflectance profile: bar (below the threshold) or space.
struct Element {
  bool bar = false;
  double begin = 0, end = 0;  ///< t of its edges
  double extreme = 0;         ///< lowest reflectance of a bar, highest of a space
  double nonuniformity = 0;   ///< ERN: highest inner peak - lowest valley within it
};

/// The elements of profile `p` (samples every `step` from `t0`) at `threshold`.
std::vector<Element> elements(const std::vector<double>& p, double threshold, double t0,
                              double step) {
  std::vector<Element> out;
  if (p.empty()) return out;
  std::size_t start = 0;
  double begin = t0;
  for (std::size_t i = 1; i <= p.size(); ++i) {
    const bool ends = i == p.size() || (p[i] < threshold) != (p[start] < threshold);
    if (!ends) continue;
    Element e;
    e.bar = p[start] < threshold;
    e.begin = begin;
    e.end = i == p.size() ? t0 + static_cast<double>(i - 1) * step
                          : crossing(p, i, threshold, t0, step);
    double lo = p[start], hi = p[start];
    for (std::size_t k = start; k < i; ++k) lo = std::min(lo, p[k]), hi = std::max(hi, p[k]);
    e.extreme = e.bar ? lo : hi;
    // Inner peaks of a bar (valleys of a space) against its extreme.
    for (std::size_t k = start + 1; k + 1 < i; ++k) {
      const bool peak = p[k] > p[k - 1] && p[k] >= p[k + 1];
      const bool valley = p[k] < p[k - 1] && p[k] <= p[k + 1];
      if (e.bar && peak) e.nonuniformity = std::max(e.nonuniformity, p[k] - lo);
      if (!e.bar && valley) e.nonuniformity = std::max(e.nonuniformity, hi - p[k]);
    }
    out.push_back(e);
    start = i;
    begin = e.end;
  }
  return out;
}

/// Elements (bars and spaces, first bar to last) and modules of every symbol of
/// `format`, for the symbologies of one length; {0, 0} for the others.
std::pair<std::size_t, int> fixed_structure(const std::string& format) {
  const std::optional<EanUpcLayout> layout = ean_upc_layout(format);
  if (!layout) return {0, 0};
  return {layout->elements, layout->modules};
}

/// Modules of a linear symbol of `format` with `count` elements, where the
/// symbology and the count fix it; 0 otherwise. A symbology of one length
/// fixes it whatever was counted: a profile through paper texture or noise
/// splits an element or merges two, and the symbol's extent still holds its
/// modules.
int structured_modules(const std::string& format, std::size_t count) {
  const auto n = static_cast<int>(count);
  if (format == "Code128" && n >= 13 && (n - 7) % 6 == 0) return 11 * ((n - 7) / 6) + 13;
  return fixed_structure(format).second;
}

/// The graded parameters of one scan.
struct ScanGrade {
  double r_min = 0, r_max = 0, sc = 0, ec_min = 0, modulation = 0, defects = 0, grade = 0;
};

/// One scan at offset `s` across: the profile from the quiet zone before the
/// first bar to the one after the last (at most `quiet` px each side, less
/// where the label's paper ends), graded. `expected` elements first bar to last:
/// a scan that finds another count cannot decode the symbol the others read.
ScanGrade grade_scan(const imaging::Plane& latent, const ScanLine& line, double s, double t_begin,
                     double t_end, double quiet, double paper_threshold, std::size_t expected) {
  constexpr double kStep = 0.5;
  // The quiet zones: out from the symbol while the label's paper lasts.
  auto quiet_extent = [&](double from, double direction) {
    double q = 0;
    while (q + kStep <= quiet) {
      const auto v = sample(
          latent, line.origin + (from + direction * (q + kStep)) * line.axis + s * line.across);
      if (!v || *v < paper_threshold) break;
      q += kStep;
    }
    return q;
  };
  const double t0 = t_begin - quiet_extent(t_begin - 1.5, -1) - 1.5;
  const double t1 = t_end + quiet_extent(t_end + 1.5, +1) + 1.5;
  const std::vector<double> p = profile(latent, line, s, t0, t1, kStep);
  ScanGrade g;
  if (p.size() < 4) return g;
  g.r_min = *std::min_element(p.begin(), p.end());
  g.r_max = *std::max_element(p.begin(), p.end());
  g.sc = g.r_max - g.r_min;
  if (g.sc <= 0) return g;
  const std::vector<Element> es = elements(p, g.r_min + g.sc / 2, t0, kStep);
  g.ec_min = g.sc;
  double ern = 0;
  std::size_t bars_and_spaces = 0;  // first bar to last
  for (std::size_t i = 0; i < es.size(); ++i) {
    if (i + 1 < es.size())
      g.ec_min = std::min(g.ec_min, std::abs(es[i].extreme - es[i + 1].extreme));
    ern = std::max(ern, es[i].nonuniformity);
  }
  if (es.size() >= 3)
    bars_and_spaces = es.size() - (es.front().bar ? 0 : 1) - (es.back().bar ? 0 : 1);
  g.modulation = g.ec_min / g.sc;
  g.defects = ern / g.sc;
  const bool decodes = bars_and_spaces == expected;
  g.grade = std::min({contrast_grade(g.sc), g.ec_min >= 0.15 ? 4.0 : 0.0,
                      grade_at_least(g.modulation, 0.70, 0.60, 0.50, 0.40),
                      grade_at_most(g.defects, 0.15, 0.20, 0.25, 0.30),
                      g.r_min <= 0.5 * g.r_max ? 4.0 : 0.0, decodes ? 4.0 : 0.0});
  return g;
}

/// The bars' profile along the scan line, to compare the profiles beside it with.
struct BarProfile {
  std::vector<double> samples;  ///< every px from the first bar to the last
  double mean = 0;
  double norm = 0;  ///< sum of squared deviations from the mean
};

BarProfile bar_profile(const imaging::Plane& latent, const ScanLine& line, double t_begin,
                       double t_end) {
  BarProfile ref;
  ref.samples = profile(latent, line, 0, t_begin, t_end, 1.0);
  for (double v : ref.samples) ref.mean += v;
  ref.mean /= static_cast<double>(ref.samples.size());
  for (double v : ref.samples) ref.norm += (v - ref.mean) * (v - ref.mean);
  return ref;
}

/// How far (px) across from the scan line the bars of `ref` go in `direction`
/// (+1 or -1): where the profile's projection on the centre's falls to half.
/// Steps of 2 px, then the last step halved twice and interpolated.
double bar_extent(const imaging::Plane& latent, const ScanLine& line, double t_begin, double t_end,
                  const BarProfile& ref, double direction, double limit) {
  if (ref.norm <= 0) return 0;
  // The profile at offset s, projected on the centre's (1 = the same bars).
  auto amplitude = [&](double s) {
    const std::vector<double> p = profile(latent, line, direction * s, t_begin, t_end, 1.0);
    if (p.size() != ref.samples.size()) return 0.0;  // off the image
    double pm = 0;
    for (double v : p) pm += v;
    pm /= static_cast<double>(p.size());
    double sum = 0;
    for (std::size_t i = 0; i < p.size(); ++i) sum += (p[i] - pm) * (ref.samples[i] - ref.mean);
    return sum / ref.norm;
  };
  constexpr double kStep = 2;
  double inside = 0, inside_amplitude = 1;
  for (double s = kStep; s <= limit; s += kStep) {
    const double a = amplitude(s);
    if (a >= 0.5) {
      inside = s;
      inside_amplitude = a;
      continue;
    }
    double outside = s, outside_amplitude = a;
    for (int halving = 0; halving < 2; ++halving) {
      const double mid = 0.5 * (inside + outside);
      const double am = amplitude(mid);
      (am >= 0.5 ? inside : outside) = mid;
      (am >= 0.5 ? inside_amplitude : outside_amplitude) = am;
    }
    const double f = (inside_amplitude - 0.5) / (inside_amplitude - outside_amplitude);
    return inside + std::clamp(f, 0.0, 1.0) * (outside - inside);
  }
  return limit;
}

CodeQuality measure_linear(const imaging::Plane& latent, const std::string& format,
                           const CodeCorners& corners) {
  CodeQuality q;
  q.corners = corners;
  const CodePoint left = midpoint(corners[0], corners[3]), right = midpoint(corners[1], corners[2]);
  const double span = length(right - left);
  if (span < 8) {
    q.problem = "the code is shorter than 8 px";
    return q;
  }
  ScanLine line;
  line.axis = (1 / span) * (right - left);
  line.across = {-line.axis.y, line.axis.x};
  line.origin = midpoint(left, right);
  // The bars along the decoded line: first bar's leading edge to last bar's trailing edge.
  constexpr double kStep = 0.5, kMargin = 4;
  const double t0 = -span / 2 - kMargin;
  const std::vector<double> centre = profile(latent, line, 0, t0, span / 2 + kMargin, kStep);
  if (centre.size() < 8) {
    q.problem = "the code runs off the image";
    return q;
  }
  const double lo = *std::min_element(centre.begin(), centre.end());
  const double hi = *std::max_element(centre.begin(), centre.end());
  const double threshold = (lo + hi) / 2;
  auto bars_and_spaces = [&](const std::vector<double>& p) {
    std::vector<Element> out = elements(p, threshold, t0, kStep);
    while (!out.empty() && !out.front().bar) out.erase(out.begin());
    while (!out.empty() && !out.back().bar) out.pop_back();
    return out;
  };
  std::vector<Element> es = bars_and_spaces(centre);
  if (es.size() < 3 || hi - lo < 0.05) {
    q.problem = "no bars along the decoded line";
    return q;
  }
  // A Code 128 count that is no symbol's (texture or noise on the line splits
  // a bar or bridges a space): counted again on the lines kAlongBars px either
  // side averaged, which follow the bars, and taken if that is a symbol's
  // count. (The symbologies of one length need no count; the others' counts
  // cannot be checked.)
  if (format == "Code128" && structured_modules(format, es.size()) == 0) {
    constexpr int kAlongBars = 4;
    std::vector<double> averaged(centre.size(), 0.0);
    bool whole = true;
    for (int s = -kAlongBars; s <= kAlongBars && whole; ++s) {
      const std::vector<double> p = profile(latent, line, s, t0, span / 2 + kMargin, kStep);
      whole = p.size() == centre.size();
      for (std::size_t i = 0; whole && i < p.size(); ++i)
        averaged[i] += p[i] / (2 * kAlongBars + 1);
    }
    std::vector<Element> again = whole ? bars_and_spaces(averaged) : std::vector<Element>{};
    if (structured_modules(format, again.size()) > 0) es = std::move(again);
  }
  const double t_begin = es.front().begin, t_end = es.back().end;
  q.modules = structured_modules(format, es.size());
  if (q.modules > 0) {
    q.module_px = (t_end - t_begin) / q.modules;
  } else {
    // Symbologies of narrow and wide elements: the narrow ones' mean width.
    std::vector<double> widths;
    for (const Element& e : es) widths.push_back(e.end - e.begin);
    std::sort(widths.begin(), widths.end());
    const double narrow_limit = 1.5 * widths[widths.size() / 10];
    double sum = 0;
    int n = 0;
    for (double w : widths)
      if (w <= narrow_limit) sum += w, ++n;
    q.module_px = sum / n;
    q.modules = static_cast<int>(std::lround((t_end - t_begin) / q.module_px));
  }
  // The bars' ends across: where the centre's profile fades out either side.
  const BarProfile bars = bar_profile(latent, line, t_begin, t_end);
  const double up = bar_extent(latent, line, t_begin, t_end, bars, -1, 2 * span);
  const double down = bar_extent(latent, line, t_begin, t_end, bars, +1, 2 * span);
  auto at = [&](double t, double s) { return line.origin + t * line.axis + s * line.across; };
  q.corners = {at(t_begin, -up), at(t_end, -up), at(t_end, down), at(t_begin, down)};
  // Ten scans over 10%-90% of the bar height, each expected to find the
  // symbology's elements where it fixes them, else the centre line's.
  const std::size_t fixed_elements = fixed_structure(format).first;
  const std::size_t expected_elements = fixed_elements > 0 ? fixed_elements : es.size();
  const double height = up + down;
  const double paper = threshold;  // beyond the quiet zone the belt is darker than this
  constexpr int kScans = 10;
  double sum_grade = 0;
  for (int i = 0; i < kScans; ++i) {
    const double s = -up + height * (0.1 + 0.8 * (i + 0.5) / kScans);
    const ScanGrade g =
        grade_scan(latent, line, s, t_begin, t_end, 10 * q.module_px, paper, expected_elements);
    q.r_min += g.r_min / kScans;
    q.r_max += g.r_max / kScans;
    q.symbol_contrast += g.sc / kScans;
    q.edge_contrast += g.ec_min / kScans;
    q.modulation += g.modulation / kScans;
    q.defects += g.defects / kScans;
    sum_grade += g.grade;
  }
  q.scans = kScans;
  q.grade_value = sum_grade / kScans;
  q.grade = grade_letter(q.grade_value);
  q.measured = true;
  return q;
}

// ---- matrix codes --------------------------------------------------------

/// The point at (u, v) in [0, 1]^2 of the quadrilateral `c` (bilinear).
CodePoint in_quad(const CodeCorners& c, double u, double v) {
  return (1 - u) * (1 - v) * c[0] + u * (1 - v) * c[1] + u * v * c[2] + (1 - u) * v * c[3];
}

/// Reflectance at the centres of a cols x rows grid over the quadrilateral `c`,
/// row by row into `out`; false if a centre is off the image.
bool sample_grid(const imaging::Plane& latent, const CodeCorners& c, int cols, int rows,
                 std::vector<double>& out) {
  out.resize(static_cast<std::size_t>(cols) * rows);
  for (int r = 0; r < rows; ++r)
    for (int k = 0; k < cols; ++k) {
      const auto v = sample(latent, in_quad(c, (k + 0.5) / cols, (r + 0.5) / rows));
      if (!v) return false;
      out[static_cast<std::size_t>(r) * cols + k] = *v;
    }
  return true;
}

/// Cycles over `g` of its strongest periodic component among `lowest` .. size/2.
int strongest_cycles(const std::vector<double>& g, int lowest) {
  const auto n = static_cast<int>(g.size());
  double mean = 0;
  for (double v : g) mean += v;
  mean /= n;
  int best = 0;
  double best_power = 0;
  for (int k = lowest; k <= n / 2; ++k) {
    std::complex<double> sum = 0;
    for (int i = 0; i < n; ++i)
      sum += (g[i] - mean) * std::polar(1.0, -2 * std::numbers::pi * k * i / n);
    if (std::norm(sum) > best_power) best_power = std::norm(sum), best = k;
  }
  return best;
}

CodeQuality measure_matrix(const imaging::Plane& latent, const CodeCorners& c) {
  CodeQuality q;
  q.corners = c;
  const double width = 0.5 * (length(c[1] - c[0]) + length(c[2] - c[3]));
  const double height = 0.5 * (length(c[3] - c[0]) + length(c[2] - c[1]));
  const int samples = static_cast<int>(std::ceil(std::max(width, height)));
  if (samples < 16) {
    q.problem = "the symbol is smaller than 16 px";
    return q;
  }
  // The symbol resampled square; the edges between modules fall on its module grid.
  std::vector<double> patch;
  if (!sample_grid(latent, c, samples, samples, patch)) {
    q.problem = "the symbol runs off the image";
    return q;
  }
  std::vector<double> gx(samples - 1, 0.0), gy(samples - 1, 0.0);
  for (int j = 0; j < samples; ++j)
    for (int i = 0; i + 1 < samples; ++i) {
      gx[i] += std::abs(patch[j * samples + i + 1] - patch[j * samples + i]);
      gy[i] += std::abs(patch[(i + 1) * samples + j] - patch[i * samples + j]);
    }
  constexpr int kFewestModules = 8;  // no matrix symbology has fewer per side
  const int cols = strongest_cycles(gx, kFewestModules);
  const int rows = strongest_cycles(gy, kFewestModules);
  if (cols == 0 || rows == 0) {
    q.problem = "no module grid inside the symbol";
    return q;
  }
  q.modules = cols;
  q.module_px = width / cols;
  // The reflectance at each module's centre (inside the patch sampled above, so inside the
  // image; checked all the same).
  std::vector<double> centres;
  if (!sample_grid(latent, c, cols, rows, centres)) {
    q.problem = "the symbol runs off the image";
    return q;
  }
  const auto [lo, hi] = std::minmax_element(centres.begin(), centres.end());
  q.r_min = *lo;
  q.r_max = *hi;
  q.symbol_contrast = q.r_max - q.r_min;
  if (q.symbol_contrast > 0) {
    const double threshold = (q.r_max + q.r_min) / 2;
    std::vector<double> modulation;
    for (double v : centres)
      modulation.push_back(std::abs(v - threshold) / (q.symbol_contrast / 2));
    std::nth_element(modulation.begin(), modulation.begin() + modulation.size() / 20,
                     modulation.end());
    q.modulation = modulation[modulation.size() / 20];
  }
  q.axial_nonuniformity =
      std::abs(q.module_px - height / rows) / (0.5 * (q.module_px + height / rows));
  q.scans = 1;
  q.grade_value = std::min({contrast_grade(q.symbol_contrast),
                            grade_at_least(q.modulation, 0.50, 0.40, 0.30, 0.20),
                            grade_at_most(q.axial_nonuniformity, 0.06, 0.08, 0.10, 0.12)});
  q.grade = grade_letter(q.grade_value);
  q.measured = true;
  return q;
}

}  // namespace

bool is_linear_format(const std::string& format) {
  for (const char* f : {"Code128", "Code39", "Code93", "Codabar", "EAN-8", "EAN-13", "ITF", "UPC-A",
                        "UPC-E", "DataBar", "DataBarExpanded"})
    if (format == f) return true;
  return false;
}

char grade_letter(double value) {
  return value >= 3.5 ? 'A' : value >= 2.5 ? 'B' : value >= 1.5 ? 'C' : value >= 0.5 ? 'D' : 'F';
}

CodeQuality measure_code(const imaging::Plane& latent, const std::string& format,
                         const CodeCorners& corners) {
  if (latent.width < 2 || latent.height < 2) {
    CodeQuality q;
    q.corners = corners;
    q.problem = "the image is empty";
    return q;
  }
  return is_linear_format(format) ? measure_linear(latent, format, corners)
                                  : measure_matrix(latent, corners);
}

}  // namespace flutterscan::reader
