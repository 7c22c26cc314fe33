#include "reader/bar_pattern_fit.hpp"

#include <ZXing/BarcodeFormat.h>
#include <ZXing/BitMatrix.h>
#include <ZXing/MultiFormatWriter.h>

#include <opencv2/core.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <exception>
#include <limits>
#include <optional>
#include <vector>

namespace flutterscan::reader {
namespace {

/// The widths of the ten EAN/UPC "L" characters (digits 0-9; space, bar,
/// space, bar: ISO/IEC 15420). An "R" character has the same widths starting
/// with a bar, a "G" character them reversed starting with a space.
constexpr std::array<std::array<int, 4>, 10> kLWidths = {{{3, 2, 1, 1},
                                                          {2, 2, 2, 1},
                                                          {2, 1, 2, 2},
                                                          {1, 4, 1, 1},
                                                          {1, 1, 3, 2},
                                                          {1, 2, 3, 1},
                                                          {1, 1, 1, 4},
                                                          {1, 3, 1, 2},
                                                          {1, 2, 1, 3},
                                                          {3, 1, 1, 2}}};
constexpr int kCharacterModules = 7;

using Modules = std::vector<std::uint8_t>;  ///< 1: bar

/// Where an EAN/UPC symbol's characters lie: the module each starts at, and
/// whether a left-half character may take either parity (EAN-13's first digit
/// is told by its left half's parities; UPC-A is an EAN-13 that starts with 0,
/// judged the same way).
struct Layout {
  int modules = 0;
  std::vector<int> starts;
  int left_characters = 0;
  bool both_parities = false;
  ZXing::BarcodeFormat writer_format = ZXing::BarcodeFormat::None;
};

std::optional<Layout> layout_of(const std::string& format) {
  Layout l;
  int per_half = 0;
  if (format == "EAN-13" || format == "UPC-A") {
    per_half = 6;
    l.both_parities = true;
    l.writer_format = format == "EAN-13" ? ZXing::BarcodeFormat::EAN13 : ZXing::BarcodeFormat::UPCA;
  } else if (format == "EAN-8") {
    per_half = 4;
    l.writer_format = ZXing::BarcodeFormat::EAN8;
  } else {
    return std::nullopt;
  }
  // Start guard (3 modules), the left half, the centre guard (5), the right half, the end guard
  // (3).
  l.modules = 3 + 2 * per_half * kCharacterModules + 5 + 3;
  l.left_characters = per_half;
  for (int i = 0; i < per_half; ++i) l.starts.push_back(3 + i * kCharacterModules);
  for (int i = 0; i < per_half; ++i)
    l.starts.push_back(3 + per_half * kCharacterModules + 5 + i * kCharacterModules);
  return l;
}

/// The read value's modules, ZXing's writer's (empty if it refuses the value).
Modules modules_of(const Layout& layout, const std::string& text) {
  try {
    const ZXing::BitMatrix m =
        ZXing::MultiFormatWriter(layout.writer_format).setMargin(0).encode(text, 1, 1);
    if (m.width() != layout.modules || m.height() < 1) return {};
    Modules out(static_cast<std::size_t>(m.width()));
    for (int x = 0; x < m.width(); ++x) out[static_cast<std::size_t>(x)] = m.get(x, 0) ? 1 : 0;
    return out;
  } catch (const std::exception&) {
    return {};
  }
}

/// The characters allowed at a place: the L widths from a space (left half) or
/// a bar (right half), and the G widths too where `both_parities`.
std::vector<Modules> characters_allowed(bool bar_first, bool both_parities) {
  std::vector<Modules> out;
  auto add = [&](const std::array<int, 4>& widths) {
    Modules m;
    std::uint8_t colour = bar_first ? 1 : 0;
    for (const int w : widths) {
      m.insert(m.end(), static_cast<std::size_t>(w), colour);
      colour ^= 1;
    }
    out.push_back(std::move(m));
  };
  for (const auto& w : kLWidths) {
    add(w);
    if (both_parities) add({w[3], w[2], w[1], w[0]});
  }
  return out;
}

/// Bilinear value at (x, y), nullopt outside the plane (not clamped: a
/// deblurred latent overshoots).
std::optional<double> sample(const imaging::Plane& p, double x, double y) {
  if (!(x >= 0 && y >= 0 && x <= p.width - 1 && y <= p.height - 1) || p.width < 2 || p.height < 2)
    return std::nullopt;
  const int x0 = std::min(static_cast<int>(x), p.width - 2);
  const int y0 = std::min(static_cast<int>(y), p.height - 2);
  const double fx = x - x0, fy = y - y0;
  const double top = p.at(x0, y0) * (1 - fx) + p.at(x0 + 1, y0) * fx;
  const double bottom = p.at(x0, y0 + 1) * (1 - fx) + p.at(x0 + 1, y0 + 1) * fx;
  return top * (1 - fy) + bottom * fy;
}

/// Where the symbol's modules lie along the line and how blurred: its first
/// bar's leading edge and last bar's trailing edge (px along the line), its
/// bend (a label in perspective: the module width changes along the code,
/// (1 + bend) / (1 - bend) times from the first module to the last) and the
/// blur's Gaussian sigma (px).
struct Geometry {
  double begin = 0, end = 0, bend = 0, sigma = 1;
};

/// The modules' edges under `g`: edge i at u = i / modules along the code.
std::vector<double> module_edges(const Geometry& g, std::size_t modules) {
  std::vector<double> edges(modules + 1);
  for (std::size_t i = 0; i <= modules; ++i) {
    const double u = static_cast<double>(i) / static_cast<double>(modules);
    edges[i] = g.begin + (g.end - g.begin) * (u + g.bend * u * (u - 1));
  }
  return edges;
}

/// The share of bar seen by the sample at `t` (1 px wide) of `modules` between
/// `edges`, blurred by a Gaussian of `sigma` px.
class BarShare {
 public:
  BarShare(const Modules& modules, const std::vector<double>& edges, double sigma)
      : modules_(modules),
        edges_(edges),
        // The 1 px sample's box adds its variance, 1/12 px^2.
        scale_(std::sqrt(2.0 * (sigma * sigma + 1.0 / 12.0))) {}

  double at(double t) const {
    // The modules within 4.2 sigma: a module farther adds below 1e-5.
    const double reach = 3 * scale_;
    const auto from = std::lower_bound(edges_.begin(), edges_.end(), t - reach);
    const auto first =
        static_cast<std::size_t>(std::max<std::ptrdiff_t>(0, from - edges_.begin() - 1));
    double share = 0;
    for (std::size_t i = first; i < modules_.size() && edges_[i] <= t + reach; ++i) {
      if (modules_[i] == 0) continue;
      share += 0.5 * (std::erf((t - edges_[i]) / scale_) - std::erf((t - edges_[i + 1]) / scale_));
    }
    return share;
  }

 private:
  const Modules& modules_;
  const std::vector<double>& edges_;
  double scale_;
};

/// The paper's and the bars' levels along the code: the value at position u
/// (0 at the first bar's edge, 1 at the last's) is paper(u) - depth(u) times
/// the bar share, each linear in u (a real label is lit and printed unevenly:
/// a photo's spaces fell from 0.3 to 0.14 along one EAN-13).
struct Levels {
  double paper0 = 0, paper1 = 0, depth0 = 0, depth1 = 0;
  double value(double u, double share) const {
    return paper0 + paper1 * u - (depth0 + depth1 * u) * share;
  }
};

struct Fit {
  double residual = std::numeric_limits<double>::infinity();
  Levels levels;
  Geometry geometry;
};

/// Least squares of `profile` (samples at t0 + k, u = (t - origin) / span)
/// on the levels; residual infinite where the bars come out no darker than the
/// paper at either end of the code.
Fit fit_levels(const std::vector<double>& profile, double t0, double span, const BarShare& share) {
  cv::Matx44d normal = cv::Matx44d::zeros();
  cv::Vec4d rhs(0, 0, 0, 0);
  std::vector<cv::Vec4d> rows(profile.size());
  for (std::size_t k = 0; k < profile.size(); ++k) {
    const double t = t0 + static_cast<double>(k);
    const double u = t / span, g = share.at(t);
    rows[k] = cv::Vec4d(1, u, -g, -u * g);
    normal += rows[k] * rows[k].t();
    rhs += profile[k] * rows[k];
  }
  Fit f;
  cv::Vec4d x;
  if (!cv::solve(normal, rhs, x, cv::DECOMP_CHOLESKY)) return f;
  f.levels = {x[0], x[1], x[2], x[3]};
  if (x[2] <= 0 || x[2] + x[3] <= 0) return f;
  f.residual = 0;
  for (std::size_t k = 0; k < profile.size(); ++k) {
    const double e = profile[k] - rows[k].dot(x);
    f.residual += e * e;
  }
  return f;
}

/// The best fit of `modules` to `profile`, the symbol's ends searched within
/// 6 px of `begin` and `end` (where its corners put them; a read's corners
/// are found on another latent), then its bend and blur, then all finer.
Fit best_fit(const std::vector<double>& profile, double t0, const Modules& modules, double begin,
             double end) {
  const double span = end - begin;
  Fit best;
  auto consider = [&](const Geometry& g) {
    if (g.sigma <= 0 || g.end - g.begin < static_cast<double>(modules.size()) * 0.5) return;
    const std::vector<double> edges = module_edges(g, modules.size());
    Fit f = fit_levels(profile, t0, span, BarShare(modules, edges, g.sigma));
    if (f.residual < best.residual) {
      f.geometry = g;
      best = f;
    }
  };
  for (double db = -6; db <= 6; db += 1)
    for (double de = -6; de <= 6; de += 1) consider({begin + db, end + de, 0, 1.2});
  if (!std::isfinite(best.residual)) return best;
  Geometry g = best.geometry;
  for (const double sigma : {0.4, 0.8, 1.2, 1.6, 2.0, 2.5, 3.0, 3.5})
    for (double bend = -0.12; bend <= 0.121; bend += 0.04) consider({g.begin, g.end, bend, sigma});
  g = best.geometry;
  for (double db = -1; db <= 1; db += 0.5)
    for (double de = -1; de <= 1; de += 0.5) consider({g.begin + db, g.end + de, g.bend, g.sigma});
  g = best.geometry;
  for (double db = -0.25; db <= 0.25; db += 0.25)
    for (double de = -0.25; de <= 0.25; de += 0.25)
      for (const double ds : {-0.2, 0.0, 0.2})
        for (const double dbend : {-0.02, 0.0, 0.02})
          consider({g.begin + db, g.end + de, g.bend + dbend, g.sigma + ds});
  return best;
}

/// The squared residual of `modules` under `fit` over samples [k0, k1).
double residual_over(const std::vector<double>& profile, double t0, double span,
                     const Modules& modules, const std::vector<double>& edges, const Fit& fit,
                     std::size_t k0, std::size_t k1) {
  const BarShare share(modules, edges, fit.geometry.sigma);
  double r = 0;
  for (std::size_t k = k0; k < k1; ++k) {
    const double t = t0 + static_cast<double>(k);
    const double e = profile[k] - fit.levels.value(t / span, share.at(t));
    r += e * e;
  }
  return r;
}

}  // namespace

BarPatternFit fit_bar_pattern(const imaging::Plane& latent, const DecodedCode& code) {
  BarPatternFit out;
  const std::optional<Layout> layout = layout_of(code.format);
  if (!layout) {
    out.problem = "no pattern fit for format " + code.format;
    return out;
  }
  const Modules read = modules_of(*layout, code.text);
  if (read.empty()) {
    out.problem = "ZXing's writer refuses " + code.format + " value " + code.text;
    return out;
  }
  // The code's centre line, left to right in reading order, and the samples
  // along it every 1 px from 4 modules and 8 px (the ends' search and the blur)
  // before its first bar to as far after its last, or to the latent's edge if
  // it is nearer (its quiet zone at least a module wide).
  const CodeCorners& c = code.quality.corners;
  const double lx = (c[0].x + c[3].x) / 2, ly = (c[0].y + c[3].y) / 2;
  const double rx = (c[1].x + c[2].x) / 2, ry = (c[1].y + c[2].y) / 2;
  const double span = std::hypot(rx - lx, ry - ly);
  const double nominal_module = span / layout->modules;
  if (nominal_module < 0.5) {
    out.problem = "the code is shorter than half a pixel per module";
    return out;
  }
  const double ux = (rx - lx) / span, uy = (ry - ly) / span;
  const double margin = 4 * nominal_module + 8;
  double t0 = -margin;
  std::vector<double> profile;
  for (double t = -margin; t <= span + margin; t += 1) {
    const auto v = sample(latent, lx + t * ux, ly + t * uy);
    if (v) {
      if (profile.empty()) t0 = t;
      profile.push_back(*v);
    } else if (!profile.empty()) {
      break;
    }
  }
  const double last = t0 + static_cast<double>(profile.size()) - 1;
  if (profile.empty() || t0 > -nominal_module || last < span + nominal_module) {
    out.problem = "the code's line runs off the latent";
    return out;
  }
  const Fit fit = best_fit(profile, t0, read, 0, span);
  const auto n = static_cast<double>(profile.size());
  if (!std::isfinite(fit.residual) || n < 8) {
    out.problem = "no fit with bars darker than spaces";
    return out;
  }
  const double noise = std::max(fit.residual / (n - 8), 1e-12);  // eight parameters fitted
  out.judged = true;
  out.contrast = fit.levels.depth0 + fit.levels.depth1 / 2;
  out.blur_px = fit.geometry.sigma;
  out.characters = static_cast<int>(layout->starts.size());
  out.worst_margin = std::numeric_limits<double>::infinity();
  const std::vector<double> edges = module_edges(fit.geometry, read.size());
  // The samples a character's modules reach: 3 sigma of blur beyond them.
  const double reach = 3 * std::sqrt(fit.geometry.sigma * fit.geometry.sigma + 1.0 / 12.0) + 1;
  for (int i = 0; i < out.characters; ++i) {
    const auto first = static_cast<std::size_t>(layout->starts[static_cast<std::size_t>(i)]);
    const bool left = i < layout->left_characters;
    const double a = edges[first] - reach, b = edges[first + kCharacterModules] + reach;
    const auto k0 = static_cast<std::size_t>(std::clamp(std::floor(a - t0), 0.0, n));
    const auto k1 = static_cast<std::size_t>(std::clamp(std::ceil(b - t0) + 1, 0.0, n));
    const double own = residual_over(profile, t0, span, read, edges, fit, k0, k1);
    Modules other = read;
    double best_other = std::numeric_limits<double>::infinity();
    for (const Modules& ch : characters_allowed(!left, left && layout->both_parities)) {
      const auto at = read.begin() + static_cast<std::ptrdiff_t>(first);
      if (std::equal(ch.begin(), ch.end(), at)) continue;
      std::copy(ch.begin(), ch.end(), other.begin() + static_cast<std::ptrdiff_t>(first));
      best_other =
          std::min(best_other, residual_over(profile, t0, span, other, edges, fit, k0, k1));
    }
    const double margin_i = (best_other - own) / noise;
    if (margin_i < out.worst_margin) {
      out.worst_margin = margin_i;
      out.worst_character = i;
    }
  }
  return out;
}

}  // namespace flutterscan::reader
