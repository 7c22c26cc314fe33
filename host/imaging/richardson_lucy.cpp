#include "imaging/richardson_lucy.hpp"

#include <algorithm>
#include <cmath>
#include "imaging/row_pool.hpp"

namespace flutterscan::imaging {

RichardsonLucy::RichardsonLucy(std::span<const ChannelPsf> channels, int width,
                               double read_variance, const RichardsonLucySettings& settings,
                               PlanEffort effort)
    : width_(width),
      taps_([&] {
        std::size_t longest = 1;
        for (const auto& c : channels) longest = std::max(longest, c.taps.size());
        return static_cast<int>(longest);
      }()),
      extended_(width + taps_ - 1),
      fft_(row_fft_length(extended_ + taps_ - 1), effort),
      offset_(std::max(read_variance, 1e-3)),
      settings_(settings) {
  const int n = fft_.length();
  const auto bins = static_cast<std::size_t>(fft_.bins());
  for (const auto& c : channels) {
    const auto spectrum = psf_spectrum(c.taps, n);
    std::vector<std::complex<float>> scaled(bins);
    for (std::size_t j = 0; j < bins; ++j)
      scaled[j] = std::complex<float>(spectrum[j] / static_cast<double>(n));
    spectra_.push_back(std::move(scaled));
  }
  // Normaliser: latent pixel i (extended index) reaches observed n = i - (K-1) + j.
  std::vector<double> normaliser(static_cast<std::size_t>(extended_), 0.0);
  white_gain_ = 0;
  for (const auto& c : channels) {
    for (std::size_t j = 0; j < c.taps.size(); ++j) white_gain_ += c.taps[j];
    for (int i = 0; i < extended_; ++i) {
      double s = 0;
      for (std::size_t j = 0; j < c.taps.size(); ++j) {
        const int observed = i - (taps_ - 1) + static_cast<int>(j);
        if (observed >= 0 && observed < width_) s += c.taps[j];
      }
      normaliser[static_cast<std::size_t>(i)] += s;
    }
  }
  for (double value : normaliser)
    inverse_normaliser_.push_back(value > 0 ? static_cast<float>(1.0 / value) : 0.0f);
}

void RichardsonLucy::deconvolve_row(std::span<const std::span<const float>> rows,
                                    std::span<float> out, Scratch& s) const {
  const int n = fft_.length();
  const auto bins = static_cast<std::size_t>(fft_.bins());
  const auto ext = static_cast<std::size_t>(extended_);
  const auto lead = static_cast<std::size_t>(taps_ - 1);
  const float offset = static_cast<float>(offset_);
  float* x = s.x.data();

  // Start from the observation scaled to reflectance, as deconvlucy starts from the image.
  for (std::size_t i = 0; i < ext; ++i) {
    const std::size_t at = i < lead ? 0 : std::min(i - lead, static_cast<std::size_t>(width_ - 1));
    double sum = 0;
    for (const auto& row : rows) sum += row[at];
    x[i] = static_cast<float>(std::max(1e-3, sum / white_gain_));
  }

  for (std::size_t c = 0; c < rows.size(); ++c)
    for (int m = 0; m < width_; ++m)
      s.observed[c][static_cast<std::size_t>(m)] = rows[c][static_cast<std::size_t>(m)] + offset;

  float* real = s.real.data();
  float* spectrum = s.spectrum.data();
  float* work = s.work.data();
  float* sum = s.sum.data();
  for (int iteration = 0; iteration < settings_.iterations; ++iteration) {
    // Biggs-Andrews: extrapolate along the last step by alpha = <g1, g2> / <g2, g2>.
    const float* base = x;
    if (settings_.accelerate && iteration >= 2) {
      float numerator = 0, denominator = 0;
      const float* step = s.step.data();
      const float* step_before = s.step_before.data();
#pragma omp simd reduction(+ : numerator, denominator)
      for (std::size_t i = 0; i < ext; ++i) {
        numerator += step[i] * step_before[i];
        denominator += step_before[i] * step_before[i];
      }
      const float alpha = denominator > 0 ? std::clamp(numerator / denominator, 0.0f, 1.0f) : 0.0f;
      for (std::size_t i = 0; i < ext; ++i)
        s.ahead[i] = std::max(0.0f, x[i] + alpha * (x[i] - s.x_previous[i]));
      base = s.ahead.data();
    }
    std::copy(base, base + ext, real);
    std::fill(real + ext, real + n, 0.0f);
    fft_.forward(real, s.spectrum.complex());
    std::fill(sum, sum + 2 * bins, 0.0f);
    for (std::size_t c = 0; c < rows.size(); ++c) {
      const float* g = reinterpret_cast<const float*>(spectra_[c].data());
      multiply_spectra(g, spectrum, work, bins);
      fft_.inverse(s.work.complex(), real);
      // Observed pixel m is linear-convolution index m + K - 1; its ratio goes to index m.
      const float* observed = s.observed[c].data();
      if (settings_.damping > 0) {
        for (int m = 0; m < width_; ++m) {
          const float predicted =
              std::max(real[static_cast<std::size_t>(m) + lead] + offset, 1e-6f);
          const double z = (observed[m] - predicted) / (settings_.damping * std::sqrt(predicted));
          real[m] =
              static_cast<float>(1.0 + std::min(1.0, z * z) * (observed[m] / predicted - 1.0));
        }
      } else {
        for (int m = 0; m < width_; ++m)
          real[m] =
              observed[m] / std::max(real[static_cast<std::size_t>(m) + lead] + offset, 1e-6f);
      }
      std::fill(real + width_, real + n, 0.0f);
      fft_.forward(real, s.work.complex());
      accumulate_spectra(g, work, sum, bins, true);
    }
    fft_.inverse(s.sum.complex(), real);
    // Correlation: latent i (extended) collects the ratio at m = i - (K-1) + j, i.e.
    // circular index i - (K-1): the first K-1 wrap around to the end of the buffer.
    std::copy(x, x + ext, s.x_previous.data());
    std::copy(s.step.data(), s.step.data() + ext, s.step_before.data());
    const float* correlation_head = real + n - lead;
    const float* correlation_tail = real - lead;
    const float* inverse_norm = inverse_normaliser_.data();
    for (std::size_t i = 0; i < ext; ++i) {
      const float back = i < lead ? correlation_head[i] : correlation_tail[i];
      const float updated =
          inverse_norm[i] > 0 ? std::max(0.0f, base[i] * back * inverse_norm[i]) : base[i];
      s.step[i] = updated - base[i];
      x[i] = updated;
    }
  }
  std::copy(x + lead, x + lead + out.size(), out.begin());
}

RichardsonLucy::Scratch RichardsonLucy::make_scratch(std::size_t channels) const {
  const auto ext = static_cast<std::size_t>(extended_);
  const auto complex_floats = static_cast<std::size_t>(2 * fft_.bins());
  Scratch scratch{{},
                  std::vector<std::span<const float>>(channels),
                  AlignedFloats(ext),
                  AlignedFloats(ext),
                  AlignedFloats(ext),
                  AlignedFloats(ext),
                  AlignedFloats(ext),
                  AlignedFloats(static_cast<std::size_t>(fft_.length())),
                  AlignedFloats(complex_floats),
                  AlignedFloats(complex_floats),
                  AlignedFloats(complex_floats)};
  for (std::size_t c = 0; c < channels; ++c)
    scratch.observed.emplace_back(static_cast<std::size_t>(width_));
  return scratch;
}

void RichardsonLucy::deconvolve(std::span<const Plane> channels, Plane& out, RowPool& pool) {
  while (static_cast<int>(workers_.size()) < pool.threads())
    workers_.push_back(make_scratch(spectra_.size()));
  pool.run(channels[0].height, [&](int first, int last, int worker) {
    Scratch& scratch = workers_[static_cast<std::size_t>(worker)];
    for (int y = first; y < last; ++y) {
      for (std::size_t c = 0; c < channels.size(); ++c) scratch.rows[c] = channels[c].row(y);
      deconvolve_row(scratch.rows, out.row(y), scratch);
    }
  });
}

Plane RichardsonLucy::deconvolve(std::span<const Plane> channels, int threads) {
  const int height = channels[0].height;
  Plane latent(width_, height);
  RowPool pool(std::max(1, std::min(threads, height)));
  deconvolve(channels, latent, pool);
  return latent;
}

}  // namespace flutterscan::imaging
