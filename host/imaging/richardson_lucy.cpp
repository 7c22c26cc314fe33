#include "imaging/richardson_lucy.hpp"

#include <algorithm>
#include <cmath>
#include "imaging/row_pool.hpp"

namespace flutterscan::imaging {

struct RichardsonLucy::Scratch {
  AlignedFloats x, x_previous, ahead;   ///< latent rows (extended length)
  AlignedFloats step, step_before;      ///< the last two RL steps, for acceleration
  AlignedFloats real;                   ///< padded real buffer
  AlignedFloats spectrum, work, sum;    ///< half-complex buffers
};

RichardsonLucy::RichardsonLucy(std::span<const ChannelPsf> channels, int width,
                               double read_variance, const RichardsonLucySettings& settings)
    : width_(width),
      taps_([&] {
        std::size_t longest = 1;
        for (const auto& c : channels) longest = std::max(longest, c.taps.size());
        return static_cast<int>(longest);
      }()),
      extended_(width + taps_ - 1),
      fft_(row_fft_length(extended_ + taps_ - 1)),
      offset_(std::max(read_variance, 1e-3)),
      settings_(settings) {
  const int n = fft_.length();
  const auto bins = static_cast<std::size_t>(fft_.bins());
  for (const auto& c : channels) {
    const auto spectrum = psf_spectrum(c.taps, n);
    std::vector<std::complex<float>> scaled(bins);
    for (std::size_t j = 0; j < bins; ++j) scaled[j] = std::complex<float>(spectrum[j] / static_cast<double>(n));
    spectra_.push_back(std::move(scaled));
  }
  // Normaliser: latent pixel i (extended index) reaches observed n = i - (K-1) + j.
  normaliser_.assign(static_cast<std::size_t>(extended_), 0.0f);
  white_gain_ = 0;
  for (const auto& c : channels) {
    for (std::size_t j = 0; j < c.taps.size(); ++j) white_gain_ += c.taps[j];
    for (int i = 0; i < extended_; ++i) {
      double s = 0;
      for (std::size_t j = 0; j < c.taps.size(); ++j) {
        const int observed = i - (taps_ - 1) + static_cast<int>(j);
        if (observed >= 0 && observed < width_) s += c.taps[j];
      }
      normaliser_[static_cast<std::size_t>(i)] += static_cast<float>(s);
    }
  }
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

  for (int iteration = 0; iteration < settings_.iterations; ++iteration) {
    // Biggs-Andrews: extrapolate along the last step by alpha = <g1, g2> / <g2, g2>.
    const float* base = x;
    if (settings_.accelerate && iteration >= 2) {
      double numerator = 0, denominator = 0;
      for (std::size_t i = 0; i < ext; ++i) {
        numerator += static_cast<double>(s.step[i]) * s.step_before[i];
        denominator += static_cast<double>(s.step_before[i]) * s.step_before[i];
      }
      const double alpha = denominator > 0 ? std::clamp(numerator / denominator, 0.0, 1.0) : 0.0;
      for (std::size_t i = 0; i < ext; ++i)
        s.ahead[i] = std::max(0.0f, x[i] + static_cast<float>(alpha) * (x[i] - s.x_previous[i]));
      base = s.ahead.data();
    }
    std::fill(s.real.data(), s.real.data() + n, 0.0f);
    std::copy(base, base + ext, s.real.data());
    fft_.forward(s.real.data(), s.spectrum.complex());
    std::complex<float>* sum = s.sum.complex();
    std::fill(sum, sum + bins, std::complex<float>{});
    for (std::size_t c = 0; c < rows.size(); ++c) {
      const std::complex<float>* g = spectra_[c].data();
      std::complex<float>* w = s.work.complex();
      for (std::size_t j = 0; j < bins; ++j) w[j] = g[j] * s.spectrum.complex()[j];
      fft_.inverse(w, s.real.data());
      // Observed pixel m is linear-convolution index m + K - 1; the ratio goes to index m.
      float* ratio = s.real.data();
      for (int m = 0; m < width_; ++m) {
        const float observed = rows[c][static_cast<std::size_t>(m)];
        const float predicted = std::max(ratio[static_cast<std::size_t>(m) + lead] + offset, 1e-6f);
        float r = (observed + offset) / predicted;
        if (settings_.damping > 0) {
          const double z = (observed + offset - predicted) / (settings_.damping * std::sqrt(predicted));
          r = static_cast<float>(1.0 + std::min(1.0, z * z) * (r - 1.0));
        }
        ratio[m] = r;
      }
      std::fill(ratio + width_, ratio + n, 0.0f);
      fft_.forward(ratio, w);
      for (std::size_t j = 0; j < bins; ++j) sum[j] += std::conj(g[j]) * w[j];
    }
    fft_.inverse(sum, s.real.data());
    // Correlation: latent i (extended) collects the ratio at m = i - (K-1) + j: index i - (K-1) mod n.
    std::copy(x, x + ext, s.x_previous.data());
    for (std::size_t i = 0; i < ext; ++i) {
      const std::size_t source = (i + static_cast<std::size_t>(n) - lead) % static_cast<std::size_t>(n);
      const float norm = normaliser_[i];
      const float updated = norm > 0 ? std::max(0.0f, base[i] * s.real.data()[source] / norm) : base[i];
      s.step_before[i] = s.step[i];
      s.step[i] = updated - base[i];
      x[i] = updated;
    }
  }
  std::copy(x + lead, x + lead + out.size(), out.begin());
}

Plane RichardsonLucy::deconvolve(std::span<const Plane> channels, int threads) const {
  const int height = channels[0].height;
  Plane latent(width_, height);
  RowPool pool(std::max(1, std::min(threads, height)));
  pool.run(height, [&](int first, int last, int) {
    const auto ext = static_cast<std::size_t>(extended_);
    const auto complex_floats = static_cast<std::size_t>(2 * fft_.bins());
    Scratch scratch{AlignedFloats(ext), AlignedFloats(ext), AlignedFloats(ext),
                    AlignedFloats(ext), AlignedFloats(ext),
                    AlignedFloats(static_cast<std::size_t>(fft_.length())),
                    AlignedFloats(complex_floats), AlignedFloats(complex_floats),
                    AlignedFloats(complex_floats)};
    std::vector<std::span<const float>> rows(channels.size());
    for (int y = first; y < last; ++y) {
      for (std::size_t c = 0; c < channels.size(); ++c) rows[c] = channels[c].row(y);
      deconvolve_row(rows, latent.row(y), scratch);
    }
  });
  return latent;
}

}  // namespace flutterscan::imaging
