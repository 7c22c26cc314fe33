#include "bench/envelope_formula.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <vector>

#include "imaging/deblur.hpp"
#include "imaging/joint_wiener.hpp"

namespace flutterscan::bench {
namespace {

/// The spectrum of `taps` at angular frequency `w` (radians per pixel).
std::complex<double> spectrum_at(const std::vector<double>& taps, double w) {
  std::complex<double> sum = 0;
  for (std::size_t j = 0; j < taps.size(); ++j)
    sum += taps[j] * std::polar(1.0, -w * static_cast<double>(j));
  return sum;
}

}  // namespace

double normalized_sinc(double x) {
  if (std::abs(x) < 1e-12) return 1.0;
  const double a = std::numbers::pi * x;
  return std::sin(a) / a;
}

ReadMargin read_margin(const imaging::CaptureModel& model, double module_px, double contrast,
                       double mean_reflectance) {
  const double lambda = 1.0 / imaging::kLabelGradientVariance;
  std::vector<std::vector<double>> psfs;
  std::vector<double> variance;
  for (int c = 0; c < model.channels; ++c) {
    psfs.push_back(imaging::channel_psf(model, c));
    variance.push_back(imaging::channel_noise_variance(
        model, mean_reflectance * imaging::channel_white_electrons(model, c)));
  }
  // S(w) on the bins of an n-point real FFT, n well above the PSF's length.
  int n = 1024;
  for (const auto& taps : psfs)
    while (n < 4 * static_cast<int>(taps.size())) n *= 2;
  std::vector<double> s(static_cast<std::size_t>(n / 2 + 1), 0.0);
  for (std::size_t c = 0; c < psfs.size(); ++c) {
    const auto g = imaging::psf_spectrum(psfs[c], n);
    for (std::size_t b = 0; b < s.size(); ++b) s[b] += std::norm(g[b]) / variance[c];
  }
  // Mean over the full circle of the noise's power: interior bins count twice.
  double noise_power = 0;
  for (std::size_t b = 0; b < s.size(); ++b) {
    const double w = 2 * std::numbers::pi * static_cast<double>(b) / n;
    const double d = s[b] + lambda * imaging::label_prior_power(w);
    const double weight = (b == 0 || static_cast<int>(b) == n / 2) ? 1.0 : 2.0;
    if (d > 0) noise_power += weight * s[b] / (d * d);
  }
  ReadMargin out;
  out.noise = std::sqrt(noise_power / n);
  // The worst transfer over the symbol's band: elements of 1 to 4 modules, w from
  // pi / 4m to pi / m (a zero of the motion's box anywhere in it loses the label).
  const double wm = std::numbers::pi / module_px;
  const auto transfer = [&](double sw, double w) {
    return sw / (sw + lambda * imaging::label_prior_power(w));
  };
  double sm = 0;
  for (std::size_t c = 0; c < psfs.size(); ++c)
    sm += std::norm(spectrum_at(psfs[c], wm)) / variance[c];
  out.transfer = transfer(sm, wm);
  for (std::size_t b = 1; b < s.size(); ++b) {
    const double w = 2 * std::numbers::pi * static_cast<double>(b) / n;
    if (w >= wm / 4 && w <= wm) out.transfer = std::min(out.transfer, transfer(s[b], w));
  }
  out.amplitude = 2 / std::numbers::pi * contrast * normalized_sinc(0.5 / module_px) * out.transfer;
  return out;
}

double formula_speed(const std::function<imaging::CaptureModel(double)>& model_at, double module_px,
                     double low, double high, double precision, double z) {
  const auto reads = [&](double v) { return read_margin(model_at(v), module_px).margin(z) >= 0; };
  // The last grid speed that reads, and the grid speed above it.
  const double step = 1.02;
  double pass = 0, fail = 0;
  for (double v = low; v <= high; v *= step) {
    if (reads(v)) {
      pass = v;
      fail = 0;
    } else if (fail == 0) {
      fail = v;
    }
  }
  if (pass == 0) return 0.0;
  if (fail == 0) return high;
  while (fail / pass > 1 + precision) {
    const double mid = std::sqrt(pass * fail);
    (reads(mid) ? pass : fail) = mid;
  }
  return pass;
}

double lit_motion_modules(sim::SceneKind kind) {
  return kind == sim::SceneKind::kCode128 || kind == sim::SceneKind::kEan13 ? 1.0 : 2.0;
}

double lit_motion_speed(double modules, double module_px, double mm_per_px, double lit_ms) {
  return modules * module_px * mm_per_px / lit_ms;
}

}  // namespace flutterscan::bench
