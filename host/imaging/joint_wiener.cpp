#include "imaging/joint_wiener.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace flutterscan::imaging {

std::vector<float> periodic_blend(int width, int padded) {
  const int gap = padded - width;
  std::vector<float> blend(static_cast<std::size_t>(std::max(0, gap)));
  for (int i = 0; i < gap; ++i) {
    const double t = (i + 1.0) / (gap + 1.0);
    blend[static_cast<std::size_t>(i)] =
        static_cast<float>(0.5 - 0.5 * std::cos(std::numbers::pi * t));
  }
  return blend;
}

void extend_row_periodically(std::span<float> padded, int width, std::span<const float> blend) {
  const float last = padded[static_cast<std::size_t>(width - 1)];
  const float step = padded[0] - last;
  float* tail = padded.data() + width;
  for (std::size_t i = 0; i < blend.size(); ++i) tail[i] = last + step * blend[i];
}

void filter_and_sum_channels(const RowFft& fft,
                             std::span<const std::vector<std::complex<float>>> filters, int width,
                             std::span<const float> blend, std::span<AlignedFloats> padded,
                             AlignedFloats& spectrum, float* sum) {
  const auto bins = static_cast<std::size_t>(fft.bins());
  for (std::size_t c = 0; c < filters.size(); ++c) {
    extend_row_periodically(padded[c].span(), width, blend);
    fft.forward(padded[c].data(), spectrum.complex());
    const float* filter = reinterpret_cast<const float*>(filters[c].data());
    if (c == 0)
      multiply_spectra(filter, spectrum.data(), sum, bins);
    else
      accumulate_spectra(filter, spectrum.data(), sum, bins, false);
  }
}

namespace {

/// Extends the complex row `pair` (a + i b, its first `width` values loaded) to
/// width + blend.size() values: each part as extend_row_periodically() extends a row.
void extend_pair_periodically(float* __restrict pair, int width, std::span<const float> blend) {
  const auto w = static_cast<std::size_t>(width);
  const float last_a = pair[2 * (w - 1)], step_a = pair[0] - last_a;
  const float last_b = pair[2 * (w - 1) + 1], step_b = pair[1] - last_b;
  float* __restrict tail = pair + 2 * w;
  for (std::size_t i = 0; i < blend.size(); ++i) {
    tail[2 * i] = last_a + step_a * blend[i];
    tail[2 * i + 1] = last_b + step_b * blend[i];
  }
}

}  // namespace

double label_prior_power(double w) {
  // Twice the gradient power: seen through the pixels' box aperture each printed
  // edge spreads over two pixels, which about halves the latent's gradient variance.
  const double gradient = 2 * (2.0 - 2.0 * std::cos(w));
  const double half = w / 2;  // pi f
  const double aperture = half == 0 ? 1.0 : std::sin(half) / half;
  return gradient / std::pow(aperture, 4);
}

std::vector<std::complex<double>> psf_spectrum(std::span<const double> taps, int n) {
  return real_dft_bins(taps, n);
}

namespace {

int padded_row_length(std::span<const ChannelPsf> channels, int width) {
  std::size_t longest = 1;
  for (const auto& c : channels) longest = std::max(longest, c.taps.size());
  return row_fft_length(width + static_cast<int>(longest));
}

/// conj(G_c) / v_c / D per channel on bins 0..n/2, D = sum_c |G_c|^2 / v_c + lambda P.
std::vector<std::vector<std::complex<double>>> wiener_transfer(std::span<const ChannelPsf> channels,
                                                               int n, double lambda) {
  const std::size_t bins = static_cast<std::size_t>(n) / 2 + 1;
  std::vector<std::vector<std::complex<double>>> spectra;
  std::vector<double> denominator(bins, 0.0);
  for (const auto& c : channels) {
    spectra.push_back(psf_spectrum(c.taps, n));
    for (std::size_t j = 0; j < bins; ++j)
      denominator[j] += std::norm(spectra.back()[j]) / c.noise_variance;
  }
  for (std::size_t j = 0; j < bins; ++j) {
    const double w = 2.0 * std::numbers::pi * static_cast<double>(j) / n;
    denominator[j] += lambda * label_prior_power(w);
    if (denominator[j] <= 0) denominator[j] = 1e-30;
  }
  for (std::size_t c = 0; c < channels.size(); ++c)
    for (std::size_t j = 0; j < bins; ++j)
      spectra[c][j] = std::conj(spectra[c][j]) / channels[c].noise_variance / denominator[j];
  return spectra;
}

}  // namespace

JointWiener::JointWiener(std::span<const ChannelPsf> channels, int width, double lambda,
                         PlanEffort effort)
    : JointWiener(wiener_transfer(channels, padded_row_length(channels, width), lambda),
                  padded_row_length(channels, width), width, effort) {}

JointWiener::JointWiener(std::span<const std::vector<std::complex<double>>> transfer, int n,
                         int width, PlanEffort effort)
    : width_(width), fft_(n, effort) {
  const auto size = static_cast<std::size_t>(n);
  const std::size_t bins = size / 2 + 1;
  for (const auto& t : transfer) {
    AlignedFloats filter(2 * size);
    std::complex<float>* bins_of = filter.complex();
    for (std::size_t j = 0; j < bins; ++j) {
      bins_of[j] = std::complex<float>(t[j] / static_cast<double>(n));
      if (j > 0 && j < size - j) bins_of[size - j] = std::conj(bins_of[j]);  // a real filter's
    }
    // A real filter's DC and Nyquist bins are real; any rounding left in their
    // imaginary parts would mix the two rows of a pair.
    bins_of[0].imag(0.0f);
    bins_of[size / 2].imag(0.0f);
    // A constant row m_c has bin 0 = n m_c and nothing else: its latent is
    // sum_c Re(filter_c[0]) n m_c everywhere.
    dc_gains_.push_back(bins_of[0].real() * static_cast<float>(n));
    filters_.push_back(std::move(filter));
  }
  blend_ = periodic_blend(width, n);
}

void JointWiener::skip_flat_rows(std::vector<double> base_variance) {
  flat_base_variance_ = std::move(base_variance);
  flat_base_variance_.resize(filters_.size(), 0.0);
}

template <typename LevelOf>
bool JointWiener::fill_if_flat(const LevelOf& level_of, std::span<float> out) const {
  const std::size_t n = static_cast<std::size_t>(width_);
  if (flat_base_variance_.empty() || n < 2) return false;
  // Stretches of kFlatRowStretch samples (the last takes the remainder), each
  // judged about the row's mean: a small code on a wide row, or one stretch's
  // level off the rest's, is not averaged away by the row's other samples.
  const std::size_t stretches = std::max<std::size_t>(1, n / kFlatRowStretch);
  const std::size_t shortest = n / stretches;
  // A sample variance of m noise samples has a relative standard error of about sqrt(2 / m).
  const double allowed = 1 + kFlatRowSigmas * std::sqrt(2.0 / static_cast<double>(shortest));
  float fill = 0;
  for (std::size_t c = 0; c < filters_.size(); ++c) {
    const RowLevel level = level_of(c);
    const float mean = level.mean(n);
    const double noise = flat_base_variance_[c] + std::max(0.0, static_cast<double>(mean));
    if (!(level.worst_mean_square <= allowed * noise)) return false;
    fill += dc_gains_[c] * mean;
  }
  std::fill(out.begin(), out.end(), fill);
  return true;
}

JointWiener::Scratch JointWiener::make_scratch() const {
  const auto complex_floats = 2 * static_cast<std::size_t>(fft_.length());
  Scratch s{{},
            {},
            {},
            {},
            AlignedFloats(complex_floats),
            AlignedFloats(complex_floats),
            AlignedFloats(complex_floats),
            AlignedFloats(complex_floats),
            0};
  const auto width = static_cast<std::size_t>(width_);
  for (std::size_t c = 0; c < filters_.size(); ++c) {
    s.first.emplace_back(width);
    s.second.emplace_back(width);
    s.first_rows.push_back(s.first.back().span());
    s.second_rows.push_back(s.second.back().span());
  }
  return s;
}

void JointWiener::deconvolve_pair(Scratch& s, std::span<float> a, std::span<float> b) const {
  const auto bins = static_cast<std::size_t>(fft_.length());
  for (std::size_t c = 0; c < filters_.size(); ++c) {
    interleave_rows(s.first[c].data(), b.empty() ? nullptr : s.second[c].data(),
                    static_cast<std::size_t>(width_), s.pair.data());
    extend_pair_periodically(s.pair.data(), width_, blend_);
    fft_.forward(s.pair.complex(), s.spectrum.complex());
    if (c == 0)
      multiply_spectra(filters_[c].data(), s.spectrum.data(), s.sum.data(), bins);
    else
      accumulate_spectra(filters_[c].data(), s.spectrum.data(), s.sum.data(), bins, false);
  }
  fft_.inverse(s.sum.complex(), s.out.complex());
  deinterleave_rows(s.out.data(), a, b);
}

template <typename LoadUnlessFlat>
void JointWiener::deconvolve_rows(const LoadUnlessFlat& load_unless_flat, int height, Plane& out,
                                  RowPool& pool) {
  while (static_cast<int>(workers_.size()) < pool.threads()) workers_.push_back(make_scratch());
  for (Scratch& scratch : workers_) scratch.flat_rows = 0;
  pool.run(height, [&](int first, int last, int worker) {
    Scratch& s = workers_[static_cast<std::size_t>(worker)];
    // Rows that are not flat go in pairs; `waiting` holds the first of a pair.
    int waiting = -1;
    for (int y = first; y < last; ++y) {
      const auto rows = waiting < 0 ? std::span(s.first_rows) : std::span(s.second_rows);
      if (load_unless_flat(y, rows, out.row(y))) {
        ++s.flat_rows;
        continue;
      }
      if (waiting < 0) {
        waiting = y;
        continue;
      }
      deconvolve_pair(s, out.row(waiting), out.row(y));
      waiting = -1;
    }
    if (waiting >= 0) deconvolve_pair(s, out.row(waiting), {});
  });
  flat_rows_ = 0;
  for (const Scratch& scratch : workers_) flat_rows_ += scratch.flat_rows;
}

void JointWiener::deconvolve(const RowLoader& load, int height, Plane& out, RowPool& pool) {
  deconvolve_rows(
      [&](int y, std::span<const std::span<float>> rows, std::span<float> out_row) {
        load(y, rows);
        return fill_if_flat([&](std::size_t c) { return row_level(rows[c]); }, out_row);
      },
      height, out, pool);
}

JointWiener::RowLoader plane_row_loader(std::span<const Plane> channels) {
  return [channels](int y, std::span<const std::span<float>> rows) {
    for (std::size_t c = 0; c < rows.size(); ++c) {
      const auto source = channels[c].row(y);
      std::copy(source.begin(), source.end(), rows[c].begin());
    }
  };
}

Plane JointWiener::deconvolve(std::span<const Plane> channels, int threads,
                              const RowLevels* levels) {
  const int height = channels[0].height;
  Plane latent = Plane::uninitialised(width_, height);  // every row written below
  RowPool pool(std::max(1, std::min(threads, height)));
  const bool known = levels != nullptr &&
                     levels->fits(static_cast<int>(channels.size()), height, channels[0].width);
  // A row is judged flat where it lies, from its levels when they are known;
  // only a row to transform is copied (on a belt most rows are flat: reading
  // them again was most of their cost).
  deconvolve_rows(
      [&](int y, std::span<const std::span<float>> rows, std::span<float> out_row) {
        const auto level_of = [&](std::size_t c) {
          return known ? levels->at(static_cast<int>(c), y) : row_level(channels[c].row(y));
        };
        if (fill_if_flat(level_of, out_row)) return true;
        for (std::size_t c = 0; c < rows.size(); ++c)
          std::copy_n(channels[c].row(y).data(), width_, rows[c].begin());
        return false;
      },
      height, latent, pool);
  return latent;
}

}  // namespace flutterscan::imaging
