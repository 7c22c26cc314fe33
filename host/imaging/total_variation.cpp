#include "imaging/total_variation.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace flutterscan::imaging {
namespace {

/// One relaxed ADMM update of a split of d = D x (Eckstein-Bertsekas over-relaxation):
/// with z = s + u the split's previous value, v = alpha d + (1 - alpha) z + u,
/// z <- v - clamp(v, low, high) (soft threshold; the box's clip is clamp itself,
/// `clip`), u <- v - z, and s <- z - u, the value the next x-update pulls D x to.
template <bool clip>
inline void relaxed_split(float d, float& s, float& u, float alpha, float low, float high) {
  const float v = alpha * d + (1 - alpha) * (s + u) + u;
  const float clamped = v < low ? low : (v > high ? high : v);  // by value: vectorises
  const float z = clip ? clamped : v - clamped;
  u = v - z;
  s = z - u;
}

/// L0's half-quadratic split: d where |d| > t, else 0.
inline float hard_threshold(float d, float t) {
  return d > t || d < -t ? d : 0.0f;
}

/// x clipped to [0, 1] (by value, so that the loops vectorise).
inline float clip_unit(float x) {
  return x < 0.0f ? 0.0f : (x > 1.0f ? 1.0f : x);
}

}  // namespace

TotalVariation::Step TotalVariation::step_of(const TotalVariationSettings& settings, int k) {
  if (settings.prior == EdgePrior::kTotalVariation) {
    const double rho_along = settings.weight_along / settings.threshold_along;
    const double rho_across = settings.weight_across / settings.threshold_across;
    return {static_cast<float>(rho_along), static_cast<float>(settings.threshold_along),
            static_cast<float>(rho_across), static_cast<float>(settings.threshold_across),
            static_cast<float>(settings.box_penalty)};
  }
  // Half-quadratic L0: hard threshold sqrt(2 mu / beta), beta from 2 mu / threshold^2 upward.
  const double growth = std::min(std::pow(settings.l0_growth, k - 1), settings.l0_most_growth);
  const double rho_along =
      2 * settings.weight_along / (settings.threshold_along * settings.threshold_along) * growth;
  const double rho_across =
      2 * settings.weight_across / (settings.threshold_across * settings.threshold_across) * growth;
  return {static_cast<float>(rho_along),
          static_cast<float>(std::sqrt(2 * settings.weight_along / rho_along)),
          static_cast<float>(rho_across),
          static_cast<float>(std::sqrt(2 * settings.weight_across / rho_across)),
          static_cast<float>(settings.box_penalty)};
}

TotalVariationSettings l0_settings() {
  TotalVariationSettings settings;
  settings.prior = EdgePrior::kL0Gradient;
  settings.weight_per_noise = 0;
  settings.weight_along = 2.0;
  settings.weight_across = 8.0;
  settings.threshold_along = 0.3;
  settings.threshold_across = 0.3;
  settings.l0_growth = 1.7;
  settings.relaxation = 1;  // half-quadratic splitting keeps no duals to relax
  return settings;
}

TotalVariation::TotalVariation(std::span<const ChannelPsf> channels, int width,
                               const TotalVariationSettings& settings, PlanEffort effort)
    : width_(width),
      fft_(
          [&] {
            std::size_t longest = 1;
            for (const auto& c : channels) longest = std::max(longest, c.taps.size());
            return row_fft_length(width + static_cast<int>(longest));
          }(),
          effort),
      pair_fft_(fft_.length(), effort),
      settings_(settings) {
  const int n = fft_.length();
  const auto bins = static_cast<std::size_t>(fft_.bins());
  data_power_.assign(bins, 0.0);
  for (const auto& c : channels) {
    const auto spectrum = psf_spectrum(c.taps, n);
    std::vector<std::complex<float>> filter(bins);
    for (std::size_t j = 0; j < bins; ++j) {
      filter[j] = std::complex<float>(std::conj(spectrum[j]) / c.noise_variance);
      data_power_[j] += std::norm(spectrum[j]) / c.noise_variance;
    }
    filters_.push_back(std::move(filter));
  }
  wiener_inverse_.resize(bins);
  double posterior_variance = 0;  // mean over all n frequencies (bins 1..n/2-1 stand for two)
  for (std::size_t j = 0; j < bins; ++j) {
    const double w = 2.0 * std::numbers::pi * static_cast<double>(j) / n;
    const double denominator = data_power_[j] + settings.wiener_lambda * (2.0 - 2.0 * std::cos(w));
    wiener_inverse_[j] = denominator > 0 ? static_cast<float>(1.0 / (denominator * n)) : 0.0f;
    const bool paired = j > 0 && 2 * static_cast<int>(j) != n;
    if (denominator > 0) posterior_variance += (paired ? 2.0 : 1.0) / denominator / n;
  }
  if (settings_.weight_per_noise > 0 && posterior_variance > 0) {
    settings_.weight_along = settings_.weight_per_noise / std::sqrt(posterior_variance);
    settings_.weight_across = settings_.across_ratio * settings_.weight_along;
    settings_.threshold_along = settings_.threshold_per_noise * std::sqrt(posterior_variance);
    settings_.threshold_across = settings_.threshold_along;
  }
  blend_ = periodic_blend(width, n);
  stride_ = static_cast<std::size_t>(n);
  spectrum_stride_ = (2 * bins + 15) / 16 * 16;
}

void TotalVariation::prepare(int height, int threads) {
  const auto n = stride_;
  const auto complex_floats = static_cast<std::size_t>(2 * fft_.bins());
  while (static_cast<int>(workers_.size()) < threads) {
    Scratch s{{},
              {},
              AlignedFloats(n),
              AlignedFloats(complex_floats),
              AlignedFloats(2 * n),
              AlignedFloats(2 * n)};
    for (std::size_t c = 0; c < filters_.size(); ++c) {
      s.padded.emplace_back(n);
      s.rows.push_back(s.padded.back().span().first(static_cast<std::size_t>(width_)));
    }
    workers_.push_back(std::move(s));
  }
  if (height == height_) return;
  height_ = height;
  const auto h = static_cast<std::size_t>(height);
  data_ = AlignedFloats(complex_floats * h);
  for (AlignedFloats* a :
       {&x_, &dual_along_, &split_along_, &dual_box_, &split_box_, &dual_across_, &split_across_})
    *a = AlignedFloats(n * h);
  spectra_ = AlignedFloats(spectrum_stride_ * h);
  pivots_ = AlignedFloats(static_cast<std::size_t>(fft_.bins()) * h);
  rhs_waiting_.resize(h);
  factored_ = {0, 0, 0};
}

void TotalVariation::load_data(int y, const RowLoader& load, Scratch& s, bool wiener_start) {
  const auto bins = static_cast<std::size_t>(fft_.bins());
  load(y, s.rows);
  float* data = data_.data() + static_cast<std::size_t>(y) * 2 * bins;
  filter_and_sum_channels(fft_, filters_, width_, blend_, s.padded, s.spectrum, data);
  if (!wiener_start) return;
  float* __restrict out = s.spectrum.data();
  const float* __restrict inverse = wiener_inverse_.data();
  for (std::size_t j = 0; j < bins; ++j) {
    out[2 * j] = data[2 * j] * inverse[j];
    out[2 * j + 1] = data[2 * j + 1] * inverse[j];
  }
  fft_.inverse(s.spectrum.complex(), s.real.data());
}

void TotalVariation::split_row(int y, float threshold, bool restart) {
  const std::size_t n = stride_;
  const std::size_t at = static_cast<std::size_t>(y) * n;
  const float* __restrict x = x_.data() + at;
  float* __restrict dual_along = dual_along_.data() + at;
  float* __restrict split_along = split_along_.data() + at;
  float* __restrict dual_box = dual_box_.data() + at;
  float* __restrict split_box = split_box_.data() + at;
  const float t = threshold;
  const std::size_t last = n - 1;  // the along-row difference wraps here (periodic latent row)
  if (settings_.prior == EdgePrior::kL0Gradient) {
#pragma omp simd
    for (std::size_t i = 0; i < last; ++i) {
      split_along[i] = hard_threshold(x[i + 1] - x[i], t);
      split_box[i] = clip_unit(x[i]);
    }
    split_along[last] = hard_threshold(x[0] - x[last], t);
    split_box[last] = clip_unit(x[last]);
    return;
  }
  if (restart) {  // no previous split: z = D x, u = 0
    std::fill(dual_along, dual_along + n, 0.0f);
    std::fill(dual_box, dual_box + n, 0.0f);
#pragma omp simd
    for (std::size_t i = 0; i < last; ++i) {
      split_along[i] = x[i + 1] - x[i];
      split_box[i] = x[i];
    }
    split_along[last] = x[0] - x[last];
    split_box[last] = x[last];
  }
  const float alpha = restart ? 1.0f : static_cast<float>(settings_.relaxation);
#pragma omp simd
  for (std::size_t i = 0; i < last; ++i)
    relaxed_split<false>(x[i + 1] - x[i], split_along[i], dual_along[i], alpha, -t, t);
  relaxed_split<false>(x[0] - x[last], split_along[last], dual_along[last], alpha, -t, t);
#pragma omp simd
  for (std::size_t i = 0; i < n; ++i)
    relaxed_split<true>(x[i], split_box[i], dual_box[i], alpha, 0.0f, 1.0f);
}

void TotalVariation::split_edge(int edge, float threshold, bool restart) {
  const std::size_t n = stride_;
  const std::size_t at = static_cast<std::size_t>(edge) * n;
  const float* __restrict upper = x_.data() + at;
  const float* __restrict lower = upper + n;
  float* __restrict dual = dual_across_.data() + at;
  float* __restrict split = split_across_.data() + at;
  const float t = threshold;
  if (settings_.prior == EdgePrior::kL0Gradient) {
#pragma omp simd
    for (std::size_t i = 0; i < n; ++i) split[i] = hard_threshold(lower[i] - upper[i], t);
    return;
  }
  if (restart) {
    std::fill(dual, dual + n, 0.0f);
#pragma omp simd
    for (std::size_t i = 0; i < n; ++i) split[i] = lower[i] - upper[i];
  }
  const float alpha = restart ? 1.0f : static_cast<float>(settings_.relaxation);
#pragma omp simd
  for (std::size_t i = 0; i < n; ++i)
    relaxed_split<false>(lower[i] - upper[i], split[i], dual[i], alpha, -t, t);
}

void TotalVariation::right_hand_side(int y, const Penalties& rho, float* __restrict real) const {
  const std::size_t n = stride_;
  const std::size_t at = static_cast<std::size_t>(y) * n;
  const float* __restrict along = split_along_.data() + at;
  const float* __restrict box = split_box_.data() + at;
  // rho_along D_along^T s_along + rho_box s_box + rho_across D_across^T s_across,
  // D^T s [i] = s[i-1] - s[i] (wrapping along the row, none beyond the first and
  // last row across).
  real[0] = rho.along * (along[n - 1] - along[0]) + rho.box * box[0];
#pragma omp simd
  for (std::size_t i = 1; i < n; ++i)
    real[i] = rho.along * (along[i - 1] - along[i]) + rho.box * box[i];
  if (y > 0) {
    const float* __restrict above = split_across_.data() + at - n;
#pragma omp simd
    for (std::size_t i = 0; i < n; ++i) real[i] += rho.across * above[i];
  }
  if (y + 1 < height_) {
    const float* __restrict below = split_across_.data() + at;
#pragma omp simd
    for (std::size_t i = 0; i < n; ++i) real[i] -= rho.across * below[i];
  }
}

void TotalVariation::transform_row(int y, Scratch& s, const Penalties& rho) {
  const std::size_t n = stride_;
  const auto bins = static_cast<std::size_t>(fft_.bins());
  const float scale = 1.0f / static_cast<float>(n);  // the inverse FFT is unnormalised
  auto data_row = [&](int row) { return data_.data() + static_cast<std::size_t>(row) * 2 * bins; };
  const int partner = y ^ 1;
  if (partner >= height_) {
    right_hand_side(y, rho, s.real.data());
    float* __restrict spectrum = spectrum_row(y);
    fft_.forward(s.real.data(), reinterpret_cast<std::complex<float>*>(spectrum));
    const float* __restrict data = data_row(y);
    for (std::size_t j = 0; j < 2 * bins; ++j) spectrum[j] = (spectrum[j] + data[j]) * scale;
    return;
  }
  const auto waiting = [&](int row) { return rhs_waiting_[static_cast<std::size_t>(row)]; };
  if (!waiting(partner)) {  // the first of the pair: it waits where its spectrum will go
    right_hand_side(y, rho, spectrum_row(y));
    rhs_waiting_[static_cast<std::size_t>(y)] = 1;
    return;
  }
  rhs_waiting_[static_cast<std::size_t>(partner)] = 0;
  right_hand_side(y, rho, s.real.data());
  const int even = y & ~1;
  const float* __restrict re = y == even ? s.real.data() : spectrum_row(even);
  const float* __restrict im = y == even ? spectrum_row(even + 1) : s.real.data();
  interleave_rows(re, im, n, s.pair.data());
  pair_fft_.forward(s.pair.complex(), s.pair_spectrum.complex());
  // Z = A + i B with A, B the rows' (Hermitian) spectra: A[k] = (Z[k] + conj Z[n-k]) / 2,
  // B[k] = (Z[k] - conj Z[n-k]) / 2i, k = 0..n/2; plus the data part, over N.
  const float* __restrict z = s.pair_spectrum.data();
  float* __restrict a = spectrum_row(even);
  float* __restrict b = spectrum_row(even + 1);
  const float* __restrict data_a = data_row(even);
  const float* __restrict data_b = data_row(even + 1);
  a[0] = (z[0] + data_a[0]) * scale;
  a[1] = data_a[1] * scale;
  b[0] = (z[1] + data_b[0]) * scale;
  b[1] = data_b[1] * scale;
  for (std::size_t k = 1; k < bins; ++k) {
    const std::size_t m = n - k;
    const float zr = z[2 * k], zi = z[2 * k + 1], mr = z[2 * m], mi = z[2 * m + 1];
    a[2 * k] = (0.5f * (zr + mr) + data_a[2 * k]) * scale;
    a[2 * k + 1] = (0.5f * (zi - mi) + data_a[2 * k + 1]) * scale;
    b[2 * k] = (0.5f * (zi + mi) + data_b[2 * k]) * scale;
    b[2 * k + 1] = (0.5f * (mr - zr) + data_b[2 * k + 1]) * scale;
  }
}

void TotalVariation::invert_pair(int y, Scratch& s) {
  const std::size_t n = stride_;
  const auto bins = static_cast<std::size_t>(fft_.bins());
  const float* __restrict a = spectrum_row(y);
  const float* __restrict b = spectrum_row(y + 1);
  float* __restrict z = s.pair.data();
  // Z = A + i B over all n bins, A[n-k] = conj A[k] (likewise B). Bins 0 and n/2
  // take the real parts only, as a real-output inverse does.
  const std::size_t nyquist = n / 2;
  z[0] = a[0];
  z[1] = b[0];
  z[2 * nyquist] = a[2 * nyquist];
  z[2 * nyquist + 1] = b[2 * nyquist];
  for (std::size_t k = 1; k < bins - 1; ++k) {
    const float ar = a[2 * k], ai = a[2 * k + 1], br = b[2 * k], bi = b[2 * k + 1];
    const std::size_t m = n - k;
    z[2 * k] = ar - bi;
    z[2 * k + 1] = ai + br;
    z[2 * m] = ar + bi;
    z[2 * m + 1] = br - ai;
  }
  pair_fft_.inverse(s.pair.complex(), s.pair_spectrum.complex());
  float* upper = x_.data() + static_cast<std::size_t>(y) * n;
  deinterleave_rows(s.pair_spectrum.data(), {upper, n}, {upper + n, n});
}

void TotalVariation::factor_across(const Penalties& rho) {
  const std::size_t n = stride_;
  const auto bins = static_cast<std::size_t>(fft_.bins());
  // Bin j's system: (d_j + rho_across k_y) x_y - rho_across (x_{y-1} + x_{y+1}) = r_y, with
  // d_j = A_j + rho_along P_j + rho_box and k_y the row's neighbour count. Pivots:
  // p_0 = d_j + rho k_0, p_y = d_j + rho k_y - rho^2 / p_{y-1}; all >= d_j > 0.
  std::vector<double> diagonal(bins), pivot(bins);
  for (std::size_t j = 0; j < bins; ++j) {
    const double w = 2.0 * std::numbers::pi * static_cast<double>(j) / static_cast<double>(n);
    diagonal[j] = data_power_[j] + rho.along * (2.0 - 2.0 * std::cos(w)) + rho.box;
  }
  const double across = rho.across;
  for (int y = 0; y < height_; ++y) {
    const double neighbours = (y > 0 ? 1.0 : 0.0) + (y + 1 < height_ ? 1.0 : 0.0);
    float* __restrict inverse = pivots_.data() + static_cast<std::size_t>(y) * bins;
    for (std::size_t j = 0; j < bins; ++j) {
      pivot[j] = diagonal[j] + across * neighbours - (y > 0 ? across * across / pivot[j] : 0.0);
      inverse[j] = static_cast<float>(1.0 / pivot[j]);
    }
  }
  factored_ = rho;
}

void TotalVariation::solve_across(int first_bin, int last_bin, float rho_across) {
  const auto bins = static_cast<std::size_t>(fft_.bins());
  const std::size_t stride = spectrum_stride_;
  const auto from = static_cast<std::size_t>(first_bin), to = static_cast<std::size_t>(last_bin);
  const float rho = rho_across;
  // Down: r_y += rho / p_{y-1} r_{y-1} (L^{-1}).
  for (int y = 1; y < height_; ++y) {
    const float* __restrict previous = spectra_.data() + static_cast<std::size_t>(y - 1) * stride;
    float* __restrict row = spectra_.data() + static_cast<std::size_t>(y) * stride;
    const float* __restrict inverse = pivots_.data() + static_cast<std::size_t>(y - 1) * bins;
    for (std::size_t j = from; j < to; ++j) {
      const float m = rho * inverse[j];
      row[2 * j] += m * previous[2 * j];
      row[2 * j + 1] += m * previous[2 * j + 1];
    }
  }
  // Up: x_y = (r_y + rho x_{y+1}) / p_y.
  for (int y = height_ - 1; y >= 0; --y) {
    float* __restrict row = spectra_.data() + static_cast<std::size_t>(y) * stride;
    const float* __restrict inverse = pivots_.data() + static_cast<std::size_t>(y) * bins;
    if (y + 1 == height_) {
      for (std::size_t j = from; j < to; ++j) {
        row[2 * j] *= inverse[j];
        row[2 * j + 1] *= inverse[j];
      }
      continue;
    }
    const float* __restrict next = row + stride;
    for (std::size_t j = from; j < to; ++j) {
      row[2 * j] = (row[2 * j] + rho * next[2 * j]) * inverse[j];
      row[2 * j + 1] = (row[2 * j + 1] + rho * next[2 * j + 1]) * inverse[j];
    }
  }
}

void TotalVariation::finish_row(int y, int first, Scratch& s, float threshold_along, bool restart,
                                const Step& next) {
  split_row(y, threshold_along, restart);
  if (y == first) return;
  split_edge(y - 1, next.threshold_across, restart);
  if (y - 1 > first) transform_row(y - 1, s, {next.rho_along, next.rho_across, next.rho_box});
}

void TotalVariation::finish_seams(std::span<const std::pair<int, int>> shares, const Step& next,
                                  bool restart) {
  const Penalties rho{next.rho_along, next.rho_across, next.rho_box};
  Scratch& s = workers_.front();
  for (const auto& [first, last] : shares)
    if (first < last && last < height_) split_edge(last - 1, next.threshold_across, restart);
  for (const auto& [first, last] : shares) {
    if (first == last) continue;
    transform_row(first, s, rho);
    if (last - 1 > first) transform_row(last - 1, s, rho);
  }
}

void TotalVariation::deconvolve(const RowLoader& load, int height, const Plane& warm_start,
                                Plane& out, RowPool& pool) {
  prepare(height, pool.threads());
  std::fill(rhs_waiting_.begin(), rhs_waiting_.end(), 0);
  const std::size_t n = stride_;
  const auto bins = static_cast<std::size_t>(fft_.bins());
  const bool own_start = warm_start.empty();
  const int iterations = settings_.iterations;
  // Each worker's rows in the row passes (RowPool gives every worker one share).
  std::vector<std::pair<int, int>> shares(workers_.size(), {0, 0});
  // Row y of x, clipped to [0, 1], into `out`: the latent, once x is final.
  auto write_out = [&](int y) {
    const float* x = x_.data() + static_cast<std::size_t>(y) * n;
    auto row = out.row(y);
    for (int i = 0; i < width_; ++i)
      row[static_cast<std::size_t>(i)] = std::clamp(x[i], 0.0f, 1.0f);
  };
  // The row passes go by pairs of rows (2k, 2k + 1): every share starts at an even row.
  const int pairs = (height + 1) / 2;
  // The first estimate, and iteration 1's splits and right-hand sides.
  const Step first = step_of(settings_, 1);
  pool.run(pairs, [&](int first_pair, int last_pair, int worker) {
    Scratch& s = workers_[static_cast<std::size_t>(worker)];
    const int from = 2 * first_pair, to = std::min(height, 2 * last_pair);
    shares[static_cast<std::size_t>(worker)] = {from, to};
    for (int y = from; y < to; ++y) {
      load_data(y, load, s, own_start);
      float* x = x_.data() + static_cast<std::size_t>(y) * n;
      if (own_start) {
        std::copy(s.real.data(), s.real.data() + n, x);
      } else {
        const auto row = warm_start.row(y);
        std::copy(row.begin(), row.end(), x);
        extend_row_periodically({x, n}, width_, blend_);
      }
      if (iterations == 0)
        write_out(y);
      else
        finish_row(y, from, s, first.threshold_along, true, first);
    }
  });
  if (iterations > 0) finish_seams(shares, first, true);
  constexpr int kBinsPerShare = 16;  // the sweeps' unit of work: 128 bytes of each spectrum row
  const int bin_shares = (static_cast<int>(bins) + kBinsPerShare - 1) / kBinsPerShare;
  for (int k = 1; k <= iterations; ++k) {
    const Step now = step_of(settings_, k);
    const Step next = step_of(settings_, k + 1);
    const Penalties rho{now.rho_along, now.rho_across, now.rho_box};
    if (!(rho == factored_)) factor_across(rho);
    pool.run(bin_shares, [&](int from, int to, int) {
      solve_across(from * kBinsPerShare, std::min(static_cast<int>(bins), to * kBinsPerShare),
                   now.rho_across);
    });
    // x's rows; unless this was the last iteration, each row's splits and the
    // next iteration's right-hand side while the row is in cache.
    const bool last = k == iterations;
    pool.run(pairs, [&](int first_pair, int last_pair, int worker) {
      Scratch& s = workers_[static_cast<std::size_t>(worker)];
      const int from = 2 * first_pair, to = std::min(height, 2 * last_pair);
      for (int y = from; y < to; y += 2) {
        if (y + 1 < to) {
          invert_pair(y, s);
        } else {  // the last row of an odd height
          fft_.inverse(reinterpret_cast<std::complex<float>*>(spectrum_row(y)),
                       x_.data() + static_cast<std::size_t>(y) * n);
        }
        for (int row = y; row < std::min(to, y + 2); ++row) {
          if (last)
            write_out(row);
          else
            finish_row(row, from, s, next.threshold_along, false, next);
        }
      }
    });
    if (!last) finish_seams(shares, next, false);
  }
}

Plane TotalVariation::deconvolve(std::span<const Plane> channels, const Plane& warm_start,
                                 int threads) {
  const int height = channels[0].height;
  Plane latent(width_, height);
  RowPool pool(std::max(1, std::min(threads, height)));
  deconvolve(plane_row_loader(channels), height, warm_start, latent, pool);
  return latent;
}

}  // namespace flutterscan::imaging
