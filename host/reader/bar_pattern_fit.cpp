#include "reader/bar_pattern_fit.hpp"

#include "imaging/bilinear.hpp"
#include "reader/ean_upc_layout.hpp"

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
#include <string>
#include <utility>
#include <vector>

namespace flutterscan::reader {
namespace {

/// The places read_ean13_by_fit() tries, best first.
constexpr std::size_t kPlacesTried = 5;

using Modules = std::vector<std::uint8_t>;  ///< 1: bar

/// A symbology the fit reads (EAN-13, UPC-A, EAN-8): its layout and ZXing's
/// writer for it. EAN-13's first digit is told by its left half's parities;
/// UPC-A is an EAN-13 that starts with 0, judged the same way.
struct Layout : EanUpcLayout {
  ZXing::BarcodeFormat writer_format = ZXing::BarcodeFormat::None;
};

std::optional<Layout> layout_of(const std::string& format) {
  const ZXing::BarcodeFormat writer = format == "EAN-13"  ? ZXing::BarcodeFormat::EAN13
                                      : format == "UPC-A" ? ZXing::BarcodeFormat::UPCA
                                      : format == "EAN-8" ? ZXing::BarcodeFormat::EAN8
                                                          : ZXing::BarcodeFormat::None;
  if (writer == ZXing::BarcodeFormat::None) return std::nullopt;
  return Layout{{*ean_upc_layout(format)}, writer};
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
  for (const auto& w : kEanLWidths) {
    add(w);
    if (both_parities) add({w[3], w[2], w[1], w[0]});
  }
  return out;
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

/// The light of each module at each sample of a profile (samples 1 px wide
/// at t0 + k), the modules lying between `edges` and blurred by a Gaussian of
/// `sigma` px: a sample's bar share is the sum of its bar modules' weights.
class ModuleWeights {
 public:
  ModuleWeights(const std::vector<double>& edges, double sigma, double t0, std::size_t samples) {
    // The 1 px sample's box adds its variance, 1/12 px^2; modules beyond
    // 4.2 sigma of a sample add below 1e-5 to it.
    const double scale = std::sqrt(2.0 * (sigma * sigma + 1.0 / 12.0)), reach = 3 * scale;
    const std::size_t modules = edges.size() - 1;
    first_.resize(samples);
    begin_.resize(samples + 1);
    for (std::size_t k = 0; k < samples; ++k) {
      const double t = t0 + static_cast<double>(k);
      const auto from = std::lower_bound(edges.begin(), edges.end(), t - reach);
      first_[k] = static_cast<std::size_t>(std::max<std::ptrdiff_t>(0, from - edges.begin() - 1));
      begin_[k] = weights_.size();
      for (std::size_t i = first_[k]; i < modules && edges[i] <= t + reach; ++i)
        weights_.push_back(
            0.5 * (std::erf((t - edges[i]) / scale) - std::erf((t - edges[i + 1]) / scale)));
    }
    begin_[samples] = weights_.size();
  }

  /// Sample k's bar share under `modules`.
  double share(std::size_t k, const Modules& modules) const {
    double s = 0;
    for (std::size_t j = begin_[k]; j < begin_[k + 1]; ++j)
      if (modules[first_[k] + j - begin_[k]] != 0) s += weights_[j];
    return s;
  }

 private:
  std::vector<std::size_t> first_, begin_;
  std::vector<double> weights_;
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

/// A profile: samples every 1 px, sample k at t0 + k px along the code's
/// line, u = t / span (0 at the corners' first bar).
struct Profile {
  std::vector<double> values;
  double t0 = 0;
  double span = 1;
  double u(std::size_t k) const { return (t0 + static_cast<double>(k)) / span; }
};

/// Least squares of the levels of `modules` seen through `weights`; residual
/// infinite where the bars come out no darker than the paper at either end.
Fit fit_levels(const Profile& p, const ModuleWeights& weights, const Modules& modules) {
  cv::Matx44d normal = cv::Matx44d::zeros();
  cv::Vec4d rhs(0, 0, 0, 0);
  std::vector<cv::Vec4d> rows(p.values.size());
  for (std::size_t k = 0; k < p.values.size(); ++k) {
    const double u = p.u(k), g = weights.share(k, modules);
    rows[k] = cv::Vec4d(1, u, -g, -u * g);
    normal += rows[k] * rows[k].t();
    rhs += p.values[k] * rows[k];
  }
  Fit f;
  cv::Vec4d x;
  if (!cv::solve(normal, rhs, x, cv::DECOMP_CHOLESKY)) return f;
  f.levels = {x[0], x[1], x[2], x[3]};
  if (x[2] <= 0 || x[2] + x[3] <= 0) return f;
  f.residual = 0;
  for (std::size_t k = 0; k < p.values.size(); ++k) {
    const double e = p.values[k] - rows[k].dot(x);
    f.residual += e * e;
  }
  return f;
}

ModuleWeights weights_of(const Profile& p, const Geometry& g, std::size_t modules) {
  return ModuleWeights(module_edges(g, modules), g.sigma, p.t0, p.values.size());
}

/// The best fit of `modules` to `p`, the symbol's ends searched within 6 px
/// of `g`'s (where its corners put them; a read's corners are found on
/// another latent), then its bend and blur, then all finer.
Fit best_fit(const Profile& p, const Modules& modules, Geometry g, double ends_reach = 6) {
  Fit best;
  auto consider = [&](const Geometry& c) {
    if (c.sigma <= 0 || c.end - c.begin < static_cast<double>(modules.size()) * 0.5) return;
    Fit f = fit_levels(p, weights_of(p, c, modules.size()), modules);
    if (f.residual < best.residual) {
      f.geometry = c;
      best = f;
    }
  };
  for (double db = -ends_reach; db <= ends_reach; db += 1)
    for (double de = -ends_reach; de <= ends_reach; de += 1)
      consider({g.begin + db, g.end + de, g.bend, g.sigma});
  if (!std::isfinite(best.residual)) return best;
  g = best.geometry;
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

/// One symbol character under a fit: the squared residual over the samples
/// its modules reach with it there, and with the best other character the
/// symbology allows there (and that character).
struct CharacterChoice {
  double own = 0;
  double best_other = std::numeric_limits<double>::infinity();
  Modules other;
};

std::vector<CharacterChoice> compare_characters(const Profile& p, const Layout& layout,
                                                const Modules& modules, const Fit& fit,
                                                const ModuleWeights& weights) {
  const std::vector<double> edges = module_edges(fit.geometry, modules.size());
  const auto n = static_cast<double>(p.values.size());
  auto residual = [&](const Modules& m, std::size_t k0, std::size_t k1) {
    double r = 0;
    for (std::size_t k = k0; k < k1; ++k) {
      const double e = p.values[k] - fit.levels.value(p.u(k), weights.share(k, m));
      r += e * e;
    }
    return r;
  };
  // The samples a character's modules reach: 3 sigma of blur beyond them.
  const double reach = 3 * std::sqrt(fit.geometry.sigma * fit.geometry.sigma + 1.0 / 12.0) + 1;
  std::vector<CharacterChoice> out;
  Modules trial = modules;
  for (std::size_t i = 0; i < layout.starts.size(); ++i) {
    const auto first = static_cast<std::size_t>(layout.starts[i]);
    const bool left = static_cast<int>(i) < layout.left_characters;
    const double a = edges[first] - reach, b = edges[first + kEanCharacterModules] + reach;
    const auto k0 = static_cast<std::size_t>(std::clamp(std::floor(a - p.t0), 0.0, n));
    const auto k1 = static_cast<std::size_t>(std::clamp(std::ceil(b - p.t0) + 1, 0.0, n));
    CharacterChoice choice;
    choice.own = residual(modules, k0, k1);
    const auto at = static_cast<std::ptrdiff_t>(first);
    for (const Modules& ch : characters_allowed(!left, left && layout.both_parities)) {
      if (std::equal(ch.begin(), ch.end(), modules.begin() + at)) continue;
      std::copy(ch.begin(), ch.end(), trial.begin() + at);
      const double r = residual(trial, k0, k1);
      if (r < choice.best_other) {
        choice.best_other = r;
        choice.other = ch;
      }
    }
    std::copy(modules.begin() + at, modules.begin() + at + kEanCharacterModules,
              trial.begin() + at);
    out.push_back(std::move(choice));
  }
  return out;
}

/// The fit's noise variance per sample (eight parameters fitted).
double noise_of(const Profile& p, const Fit& fit) {
  return std::max(fit.residual / (static_cast<double>(p.values.size()) - 8), 1e-12);
}

/// An EAN-13's modules with every character an L (left) or R (right) 0: the
/// guards, and characters to start from.
Modules ean13_start(const Layout& layout) {
  Modules m(static_cast<std::size_t>(layout.modules), 0);
  for (const int i : layout.guard_bars) m[static_cast<std::size_t>(i)] = 1;
  const Modules left = characters_allowed(false, false)[0],
                right = characters_allowed(true, false)[0];
  for (std::size_t i = 0; i < layout.starts.size(); ++i) {
    const Modules& ch = static_cast<int>(i) < layout.left_characters ? left : right;
    std::copy(ch.begin(), ch.end(), m.begin() + layout.starts[i]);
  }
  return m;
}

/// The EAN-13 value of `modules` ("" if a character or the parities name no digit).
std::string ean13_text(const Layout& layout, const Modules& modules) {
  // Digit d's L, G (left half) and R (right half) characters.
  const std::vector<Modules> left = characters_allowed(false, true);  // L0, G0, L1, G1, ...
  const std::vector<Modules> right = characters_allowed(true, false);
  std::string digits;
  std::array<int, 6> parities{};
  for (std::size_t i = 0; i < layout.starts.size(); ++i) {
    const bool is_left = static_cast<int>(i) < layout.left_characters;
    const auto at = modules.begin() + layout.starts[i];
    const std::vector<Modules>& allowed = is_left ? left : right;
    const auto found = std::find_if(allowed.begin(), allowed.end(), [&](const Modules& ch) {
      return std::equal(ch.begin(), ch.end(), at);
    });
    if (found == allowed.end()) return "";
    const auto index = static_cast<std::size_t>(found - allowed.begin());
    digits += static_cast<char>('0' + (is_left ? index / 2 : index));
    if (is_left) parities[i] = static_cast<int>(index % 2);
  }
  for (int first = 0; first < 10; ++first)
    if (kEan13FirstDigitParities[static_cast<std::size_t>(first)] == parities)
      return static_cast<char>('0' + first) + digits;
  return "";
}

/// The characters of `modules` each replaced by the one that fits best, and
/// the levels fitted again, in turn until no character changes (at most 4
/// rounds); `fit` holds the geometry and comes back with the levels.
Modules settle_characters(const Profile& p, const Layout& layout, Modules modules, Fit& fit) {
  const ModuleWeights weights = weights_of(p, fit.geometry, modules.size());
  for (int round = 0; round < 4; ++round) {
    bool changed = false;
    const std::vector<CharacterChoice> choices =
        compare_characters(p, layout, modules, fit, weights);
    for (std::size_t i = 0; i < choices.size(); ++i)
      if (choices[i].best_other < choices[i].own) {
        std::copy(choices[i].other.begin(), choices[i].other.end(),
                  modules.begin() + layout.starts[i]);
        changed = true;
      }
    const Fit levels = fit_levels(p, weights, modules);
    if (!std::isfinite(levels.residual)) {
      fit.residual = levels.residual;
      return modules;
    }
    fit.levels = levels.levels;
    fit.residual = levels.residual;
    if (!changed) break;
  }
  return modules;
}

/// Levels to start from: the paper the 90th percentile of the profile between
/// `begin` and `end`, the bars the 10th.
Levels starting_levels(const Profile& p, double begin, double end) {
  std::vector<double> inside;
  for (std::size_t k = 0; k < p.values.size(); ++k) {
    const double t = p.t0 + static_cast<double>(k);
    if (t >= begin && t <= end) inside.push_back(p.values[k]);
  }
  if (inside.size() < 10) return {};
  std::sort(inside.begin(), inside.end());
  const double paper = inside[inside.size() * 9 / 10], bars = inside[inside.size() / 10];
  return {paper, 0, std::max(paper - bars, 1e-3), 0};
}

/// Where an EAN-13 may lie along `samples` between `from` and `to`: the
/// first bar's edge and the module width (1.2 to 6 px) at which its modules'
/// centres are best explained by the symbol, each character the allowed one
/// nearest, the levels lines along the code through the guards' bars and
/// through the guards' spaces and quiet zones (5 modules each side, where the
/// samples reach): the squared residual over the contrast squared, least
/// first. Widths 3% and edges 2 px apart, the best 8 `count` again at 1% and
/// 1 px; the `count` best at least 3 modules or 5% of the width apart.
std::vector<std::pair<double, double>> ean13_places(const Layout& layout,
                                                    const std::vector<double>& samples, double from,
                                                    double to, std::size_t count) {
  const double last = static_cast<double>(samples.size()) - 1;
  auto at = [&](double x) {
    const double c = std::clamp(x, 0.0, last - 0.001);
    const auto i = static_cast<std::size_t>(c);
    return samples[i] + (samples[i + 1] - samples[i]) * (c - static_cast<double>(i));
  };
  const std::vector<Modules> left = characters_allowed(false, true);
  const std::vector<Modules> right = characters_allowed(true, false);
  struct Place {
    double score, begin, module;
  };
  const auto n = static_cast<std::size_t>(layout.modules);
  std::vector<double> centre(n);
  // A straight line through points (u, v): its values at u = 0 and 1.
  struct Line {
    double n = 0, su = 0, suu = 0, sv = 0, suv = 0;
    void add(double u, double v) {
      n += 1;
      su += u;
      suu += u * u;
      sv += v;
      suv += u * v;
    }
    std::pair<double, double> ends() const {
      const double det = n * suu - su * su;
      if (det <= 1e-12) return {sv / n, sv / n};
      const double slope = (n * suv - su * sv) / det, at0 = (sv - slope * su) / n;
      return {at0, at0 + slope};
    }
  };
  std::vector<double> dark(n), light(n);
  auto score = [&](double begin, double module) {
    for (std::size_t i = 0; i < centre.size(); ++i)
      centre[i] = at(begin + (static_cast<double>(i) + 0.5) * module);
    // The levels, each a line along the code (u = 0 to 1 over its modules):
    // the bars' through the guards' bars, the paper's through the guards'
    // spaces and the quiet zones (a label lit unevenly).
    Line bars, paper;
    auto u_of = [&](double module_index) { return (module_index + 0.5) / layout.modules; };
    for (const int i : layout.guard_bars) bars.add(u_of(i), centre[static_cast<std::size_t>(i)]);
    for (const int i : layout.guard_spaces) paper.add(u_of(i), centre[static_cast<std::size_t>(i)]);
    std::array<std::pair<double, bool>, 10> quiet{};  // the sample, and whether it is on the right
    int n_quiet = 0;
    for (int q = 1; q <= 5; ++q)
      for (const int m : {-q, layout.modules - 1 + q}) {
        const double x = begin + (m + 0.5) * module;
        if (x < 0 || x > last) continue;
        quiet[static_cast<std::size_t>(n_quiet++)] = {at(x), m > 0};
        paper.add(u_of(m), at(x));
      }
    const auto [dark0, dark1] = bars.ends();
    const auto [light0, light1] = paper.ends();
    if (light0 <= dark0 || light1 <= dark1) return std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < centre.size(); ++i) {
      const double u = u_of(static_cast<double>(i));
      dark[i] = dark0 + (dark1 - dark0) * u;
      light[i] = light0 + (light1 - light0) * u;
    }
    auto miss = [&](std::size_t i, double v, int bar) {
      const double e = v - (bar != 0 ? dark[i] : light[i]);
      return e * e;
    };
    double residual = 0;
    for (const int i : layout.guard_bars) {
      const auto k = static_cast<std::size_t>(i);
      residual += miss(k, centre[k], 1);
    }
    for (const int i : layout.guard_spaces) {
      const auto k = static_cast<std::size_t>(i);
      residual += miss(k, centre[k], 0);
    }
    for (int q = 0; q < n_quiet; ++q) {
      // A quiet zone's sample against the paper at its end of the code.
      const auto [v, right_side] = quiet[static_cast<std::size_t>(q)];
      const double e = v - (right_side ? light1 : light0);
      residual += e * e;
    }
    for (std::size_t c = 0; c < layout.starts.size(); ++c) {
      const auto first = static_cast<std::size_t>(layout.starts[c]);
      double best = std::numeric_limits<double>::infinity();
      for (const Modules& ch : static_cast<int>(c) < layout.left_characters ? left : right) {
        double r = 0;
        for (std::size_t j = 0; j < ch.size(); ++j) r += miss(first + j, centre[first + j], ch[j]);
        best = std::min(best, r);
      }
      residual += best;
    }
    const double contrast = (light0 - dark0 + light1 - dark1) / 2;
    return residual / (contrast * contrast);
  };
  std::vector<Place> coarse;
  for (double module = 1.2; module <= 6.0; module *= 1.03)
    for (double begin = from; begin + layout.modules * module <= to; begin += 2)
      coarse.push_back({score(begin, module), begin, module});
  const std::size_t refined = std::min(coarse.size(), 8 * count);
  std::partial_sort(coarse.begin(), coarse.begin() + static_cast<std::ptrdiff_t>(refined),
                    coarse.end(), [](const Place& a, const Place& b) { return a.score < b.score; });
  std::vector<Place> places;
  for (std::size_t i = 0; i < refined; ++i)
    for (const double m : {0.99, 1.0, 1.01})
      for (const double db : {-1.0, 0.0, 1.0}) {
        const double module = coarse[i].module * m, begin = coarse[i].begin + db;
        if (begin >= from && begin + layout.modules * module <= to)
          places.push_back({score(begin, module), begin, module});
      }
  std::sort(places.begin(), places.end(),
            [](const Place& a, const Place& b) { return a.score < b.score; });
  std::vector<std::pair<double, double>> out;
  for (const Place& p : places) {
    if (out.size() >= count) break;
    const bool near = std::any_of(out.begin(), out.end(), [&](const auto& o) {
      const double module = (o.second - o.first) / layout.modules;
      return std::abs(p.begin - o.first) < 3 * module && std::abs(p.module / module - 1) < 0.05;
    });
    if (!near) out.emplace_back(p.begin, p.begin + layout.modules * p.module);
  }
  return out;
}

/// read_ean13_by_fit() of a symbol whose bars seem to begin and end at
/// `begin` and `end` (within 6 px).
FittedRead read_between(const std::vector<double>& samples, double begin, double end) {
  FittedRead out;
  const Layout layout = *layout_of("EAN-13");
  const double length = end - begin;
  if (length < static_cast<double>(layout.modules) || samples.size() < 16) {
    out.problem = "the bars span less than a pixel per module";
    return out;
  }
  struct Candidate {
    Modules modules;
    Fit fit;
    Profile profile;
    bool reversed = false;
  };
  std::optional<Candidate> best;
  // The samples from 4 modules and 8 px before the bars seem to begin to as far
  // after they seem to end, as fit_bar_pattern() takes them.
  const double margin = 4 * length / layout.modules + 8;
  const auto from = static_cast<std::size_t>(std::max(0.0, std::floor(begin - margin)));
  const auto to = static_cast<std::size_t>(
      std::clamp(std::ceil(end + margin) + 1, 0.0, static_cast<double>(samples.size())));
  if (to <= from + 16) {
    out.problem = "the bars lie off the profile";
    return out;
  }
  const std::vector<double> window(samples.begin() + static_cast<std::ptrdiff_t>(from),
                                   samples.begin() + static_cast<std::ptrdiff_t>(to));
  for (const bool reversed : {false, true}) {
    Profile p;
    p.values = window;
    double b = begin - static_cast<double>(from);
    if (reversed) {
      std::reverse(p.values.begin(), p.values.end());
      b = static_cast<double>(window.size()) - 1 - (end - static_cast<double>(from));
    }
    // t = 0 at the first bar's edge as estimated.
    p.t0 = -b;
    p.span = length;
    Candidate here{ean13_start(layout), {}, p, reversed};
    // The ends 2 px apart, then 1 px apart around the best.
    auto search = [&](double step, double reach, const Geometry& around) {
      for (double db = -reach; db <= reach; db += step)
        for (double de = -reach; de <= reach; de += step) {
          Fit fit;
          fit.geometry = {around.begin + db, around.end + de, 0, 1.2};
          fit.levels = starting_levels(p, fit.geometry.begin, fit.geometry.end);
          const Modules m = settle_characters(p, layout, ean13_start(layout), fit);
          if (fit.residual < here.fit.residual) {
            here.fit = fit;
            here.modules = m;
          }
        }
    };
    search(2, 2, {0, length, 0, 1.2});
    if (!std::isfinite(here.fit.residual)) continue;
    search(1, 1, here.fit.geometry);
    if (!best || here.fit.residual < best->fit.residual) best = here;
  }
  if (best) {
    // The way round that fits better: its levels, ends (within 1 px), bend and
    // blur fitted to the characters found, and the characters again, twice.
    for (int round = 0; round < 2; ++round) {
      Fit refit = best_fit(best->profile, best->modules, best->fit.geometry, 1);
      if (!std::isfinite(refit.residual)) break;
      best->modules = settle_characters(best->profile, layout, best->modules, refit);
      if (!std::isfinite(refit.residual)) break;
      best->fit = refit;
    }
  }
  if (!best) {
    out.problem = "no fit with bars darker than spaces";
    return out;
  }
  const std::string text = ean13_text(layout, best->modules);
  if (text.empty()) {
    out.problem = "the left half's parities name no first digit";
    return out;
  }
  if (modules_of(layout, text) != best->modules) {
    out.problem = "the check digit does not hold for " + text;
    return out;
  }
  const double noise = noise_of(best->profile, best->fit);
  out.worst_margin = std::numeric_limits<double>::infinity();
  const std::vector<CharacterChoice> choices =
      compare_characters(best->profile, layout, best->modules, best->fit,
                         weights_of(best->profile, best->fit.geometry, best->modules.size()));
  for (std::size_t i = 0; i < choices.size(); ++i) {
    const double margin_i = (choices[i].best_other - choices[i].own) / noise;
    if (margin_i < out.worst_margin) {
      out.worst_margin = margin_i;
      out.worst_character = static_cast<int>(i);
    }
  }
  // Back from t along the profile read to sample indices.
  const double last = static_cast<double>(window.size()) - 1;
  const double b = best->fit.geometry.begin - best->profile.t0,
               e = best->fit.geometry.end - best->profile.t0;
  out.begin = static_cast<double>(from) + (best->reversed ? last - b : b);
  out.end = static_cast<double>(from) + (best->reversed ? last - e : e);
  if (out.worst_margin < kMinFittedReadMargin) {
    out.problem = "character " + std::to_string(out.worst_character) + " of " + text +
                  " keeps a margin of " + std::to_string(out.worst_margin);
    return out;
  }
  out.text = text;
  return out;
}

}  // namespace

FittedRead read_ean13_by_fit(const std::vector<double>& samples, double from, double to) {
  FittedRead out;
  out.problem = "no place between " + std::to_string(from) + " and " + std::to_string(to) +
                " holds an EAN-13 of modules 1.2 px or wider";
  for (const auto& [begin, end] :
       ean13_places(*layout_of("EAN-13"), samples, from, to, kPlacesTried)) {
    FittedRead here = read_between(samples, begin, end);
    if (!here.text.empty()) return here;
    if (out.text.empty()) out = here;  // the best place's reason
  }
  return out;
}

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
  Profile profile;
  profile.span = span;
  for (double t = -margin; t <= span + margin; t += 1) {
    const auto v = imaging::bilinear(latent, lx + t * ux, ly + t * uy);
    if (v) {
      if (profile.values.empty()) profile.t0 = t;
      profile.values.push_back(*v);
    } else if (!profile.values.empty()) {
      break;
    }
  }
  const double last = profile.t0 + static_cast<double>(profile.values.size()) - 1;
  if (profile.values.empty() || profile.t0 > -nominal_module || last < span + nominal_module) {
    out.problem = "the code's line runs off the latent";
    return out;
  }
  const Fit fit = best_fit(profile, read, {0, span, 0, 1.2});
  if (!std::isfinite(fit.residual) || profile.values.size() < 16) {
    out.problem = "no fit with bars darker than spaces";
    return out;
  }
  const double noise = noise_of(profile, fit);
  out.judged = true;
  out.contrast = fit.levels.depth0 + fit.levels.depth1 / 2;
  out.blur_px = fit.geometry.sigma;
  out.characters = static_cast<int>(layout->starts.size());
  out.worst_margin = std::numeric_limits<double>::infinity();
  const std::vector<CharacterChoice> choices = compare_characters(
      profile, *layout, read, fit, weights_of(profile, fit.geometry, read.size()));
  for (std::size_t i = 0; i < choices.size(); ++i) {
    const double margin_i = (choices[i].best_other - choices[i].own) / noise;
    if (margin_i < out.worst_margin) {
      out.worst_margin = margin_i;
      out.worst_character = static_cast<int>(i);
    }
  }
  return out;
}

}  // namespace flutterscan::reader
