#include "imaging/total_variation.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace flutterscan::imaging {
namespace {

/// One iteration's penalties and thresholds.
struct Step {
  float rho_along, threshold_along;
  float rho_across, threshold_across;
  float rho_box, tau;
};

/// Step `k` (1-based) of `settings`: constant for ADMM, growing for L0.
Step step_of(const TotalVariationSettings& settings, int k) {
  if (settings.prior == EdgePrior::kTotalVariation) {
    const double rho_along = settings.weight_along / settings.threshold_along;
    const double rho_across = settings.weight_across / settings.threshold_across;
    return {static_cast<float>(rho_along),
            static_cast<float>(settings.threshold_along),
            static_cast<float>(rho_across),
            static_cast<float>(settings.threshold_across),
            static_cast<float>(settings.box_penalty),
            static_cast<float>(4.0 * rho_across)};
  }
  // Half-quadratic L0: hard threshold sqrt(2 mu / beta), beta from 2 mu / threshold^2 upward.
  const double growth = std::pow(settings.l0_growth, k - 1);
  const double rho_along =
      2 * settings.weight_along / (settings.threshold_along * settings.threshold_along) * growth;
  const double rho_across =
      2 * settings.weight_across / (settings.threshold_across * settings.threshold_across) * growth;
  return {static_cast<float>(rho_along),
          static_cast<float>(std::sqrt(2 * settings.weight_along / rho_along)),
          static_cast<float>(rho_across),
          static_cast<float>(std::sqrt(2 * settings.weight_across / rho_across)),
          static_cast<float>(settings.box_penalty),
          static_cast<float>(4.0 * rho_across)};
}

}  // namespace

TotalVariationSettings l0_settings() {
  TotalVariationSettings settings;
  settings.prior = EdgePrior::kL0Gradient;
  settings.weight_per_noise = 0;
  settings.weight_along = 2.0;
  settings.weight_across = 8.0;
  settings.threshold_along = 0.3;
  settings.threshold_across = 0.3;
  settings.l0_growth = 1.25;
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
  inverse_.resize(bins);
  blend_ = periodic_blend(width, n);
  stride_ = static_cast<std::size_t>(n);
}

void TotalVariation::prepare(int height, int threads) {
  const auto n = stride_;
  const auto complex_floats = static_cast<std::size_t>(2 * fft_.bins());
  while (static_cast<int>(workers_.size()) < threads) {
    Scratch s{{}, {}, AlignedFloats(n), AlignedFloats(n), AlignedFloats(complex_floats)};
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
  for (AlignedFloats* a : {&x_, &dual_along_, &dual_box_, &partial_, &dual_across_, &across_})
    *a = AlignedFloats(n * h);
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

void TotalVariation::finish_row(int y, const float* x_new, Scratch& s, float rho_along,
                                float threshold_along, float rho_box, float tau, bool zero_duals) {
  const std::size_t n = stride_;
  const std::size_t at = static_cast<std::size_t>(y) * n;
  float* __restrict x = x_.data() + at;
  float* __restrict dual_along = dual_along_.data() + at;
  float* __restrict dual_box = dual_box_.data() + at;
  float* __restrict partial = partial_.data() + at;
  float* __restrict split = s.split.data();
  if (x_new != x) std::copy(x_new, x_new + n, x);
  const bool admm = settings_.prior == EdgePrior::kTotalVariation;
  if (zero_duals) {
    std::fill(dual_along, dual_along + n, 0.0f);
    std::fill(dual_box, dual_box + n, 0.0f);
  }
  const float t = threshold_along;
  // Along the row: z = prox(D x + u); u <- D x + u - z; split = z - u.
  for (std::size_t i = 0; i < n; ++i) {
    const float d = (i + 1 < n ? x[i + 1] : x[0]) - x[i];
    if (admm) {
      const float v = d + dual_along[i];
      const float z = v - std::clamp(v, -t, t);
      dual_along[i] = v - z;
      split[i] = 2 * z - v;
    } else {
      split[i] = std::abs(d) > t ? d : 0.0f;
    }
  }
  // partial = rho D^T split + rho_box (w - u_box) + tau x, D^T s [i] = s[i-1] - s[i].
  for (std::size_t i = 0; i < n; ++i) {
    const float back = (i > 0 ? split[i - 1] : split[n - 1]) - split[i];
    float box;
    if (admm) {
      const float v = x[i] + dual_box[i];
      const float w = std::clamp(v, 0.0f, 1.0f);
      dual_box[i] = v - w;
      box = 2 * w - v;
    } else {
      box = std::clamp(x[i], 0.0f, 1.0f);
    }
    partial[i] = rho_along * back + rho_box * box + tau * x[i];
  }
}

void TotalVariation::split_across(int edge, float threshold, bool zero_duals) {
  const std::size_t n = stride_;
  const std::size_t at = static_cast<std::size_t>(edge) * n;
  const float* __restrict upper = x_.data() + at;
  const float* __restrict lower = upper + n;
  float* __restrict dual = dual_across_.data() + at;
  float* __restrict across = across_.data() + at;
  const float t = threshold;
  if (settings_.prior == EdgePrior::kTotalVariation) {
    if (zero_duals) std::fill(dual, dual + n, 0.0f);
    // q = D x - z + u_new with z = shrink(D x + u), u_new = D x + u - z.
    for (std::size_t i = 0; i < n; ++i) {
      const float d = lower[i] - upper[i];
      const float v = d + dual[i];
      const float z = v - std::clamp(v, -t, t);
      dual[i] = v - z;
      across[i] = d + v - 2 * z;
    }
  } else {
    for (std::size_t i = 0; i < n; ++i) {
      const float d = lower[i] - upper[i];
      across[i] = std::abs(d) > t ? 0.0f : d;
    }
  }
}

void TotalVariation::deconvolve(const RowLoader& load, int height, const Plane& warm_start,
                                Plane& out, RowPool& pool) {
  prepare(height, pool.threads());
  const std::size_t n = stride_;
  const auto bins = static_cast<std::size_t>(fft_.bins());
  const bool own_start = warm_start.empty();
  const Step first = step_of(settings_, 1);
  pool.run(height, [&](int from, int to, int worker) {
    Scratch& s = workers_[static_cast<std::size_t>(worker)];
    for (int y = from; y < to; ++y) {
      load_data(y, load, s, own_start);
      if (!own_start) {
        const auto row = warm_start.row(y);
        std::copy(row.begin(), row.end(), s.real.data());
        extend_row_periodically(s.real.span(), width_, blend_);
      }
      finish_row(y, s.real.data(), s, first.rho_along, first.threshold_along, first.rho_box,
                 first.tau, true);
    }
  });
  for (int k = 1; k <= settings_.iterations; ++k) {
    const Step now = step_of(settings_, k);
    const Step next = step_of(settings_, k + 1);
    for (std::size_t j = 0; j < bins; ++j) {
      const double w = 2.0 * std::numbers::pi * static_cast<double>(j) / static_cast<double>(n);
      const double denominator =
          data_power_[j] + now.rho_along * (2.0 - 2.0 * std::cos(w)) + now.rho_box + now.tau;
      inverse_[j] = static_cast<float>(1.0 / (denominator * static_cast<double>(n)));
    }
    pool.run(height - 1, [&](int from, int to, int) {
      for (int edge = from; edge < to; ++edge) split_across(edge, now.threshold_across, k == 1);
    });
    pool.run(height, [&](int from, int to, int worker) {
      Scratch& s = workers_[static_cast<std::size_t>(worker)];
      float* __restrict real = s.real.data();
      const float rho = now.rho_across;
      for (int y = from; y < to; ++y) {
        const std::size_t at = static_cast<std::size_t>(y) * n;
        const float* __restrict partial = partial_.data() + at;
        const float* __restrict above = y > 0 ? across_.data() + at - n : nullptr;
        const float* __restrict below = y + 1 < height ? across_.data() + at : nullptr;
        // r = partial - rho D_across^T q, D^T q [y] = q[y-1] - q[y].
        if (above && below)
          for (std::size_t i = 0; i < n; ++i) real[i] = partial[i] - rho * (above[i] - below[i]);
        else if (above)
          for (std::size_t i = 0; i < n; ++i) real[i] = partial[i] - rho * above[i];
        else if (below)
          for (std::size_t i = 0; i < n; ++i) real[i] = partial[i] + rho * below[i];
        else
          std::copy(partial, partial + n, real);
        fft_.forward(real, s.spectrum.complex());
        float* __restrict spectrum = s.spectrum.data();
        const float* __restrict data = data_.data() + static_cast<std::size_t>(y) * 2 * bins;
        const float* __restrict inverse = inverse_.data();
        for (std::size_t j = 0; j < bins; ++j) {
          spectrum[2 * j] = (spectrum[2 * j] + data[2 * j]) * inverse[j];
          spectrum[2 * j + 1] = (spectrum[2 * j + 1] + data[2 * j + 1]) * inverse[j];
        }
        fft_.inverse(s.spectrum.complex(), real);
        finish_row(y, real, s, next.rho_along, next.threshold_along, next.rho_box, next.tau, false);
      }
    });
  }
  pool.run(height, [&](int from, int to, int) {
    for (int y = from; y < to; ++y) {
      const float* x = x_.data() + static_cast<std::size_t>(y) * n;
      auto row = out.row(y);
      for (int i = 0; i < width_; ++i)
        row[static_cast<std::size_t>(i)] = std::clamp(x[i], 0.0f, 1.0f);
    }
  });
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
