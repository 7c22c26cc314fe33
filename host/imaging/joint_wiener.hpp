#pragma once
// Joint Wiener deconvolution along rows (docs/algorithms.md):
//   X = sum_c conj(G_c) Y_c / v_c / (sum_c |G_c|^2 / v_c + lambda P(w)),
// G_c channel c's PSF spectrum, v_c its noise variance, P(w) = label_prior_power(w):
// the power of the gradient along the row (a smoothness prior) over the pixel
// aperture's sinc^4. With one channel it is the plain Wiener filter.
//
// Borders: each row of width W is extended to the padded FFT length N >= W + K
// (K taps of PSF) by a raised-cosine blend from the row's last value back to
// its first, so the padded row is periodic without a jump; the circular
// deconvolution then has no edge to ring at, and the extension absorbs the
// blur tail that entered the frame from the left. Output column n is the
// latent at column n (registered at the start of slot 0).
//
// Rows in pairs: the filter's impulse response is real, so two rows are
// transformed at once as the real and imaginary parts of one complex row
// (RowPairFft), filtered by the full-length spectrum, and come back as the
// real and imaginary parts of one inverse: four complex transforms for two rows
// where real-input ones took eight. The rows are interleaved into the complex
// row (and extended) in one pass, and the inverse is read back into the latent
// rows in one.
//
// Flat rows (optional, skip_flat_rows()): a row whose every channel varies
// about its mean no more than its noise would is not transformed; its latent
// is the constant the filter makes of a constant row (the DC gains times the
// channels' means). A belt between labels is such rows; anything a code could
// be printed with lifts a row's variance far above its noise, even blurred.

#include <complex>
#include <functional>
#include <span>
#include <vector>

#include "imaging/image.hpp"
#include "imaging/row_fft.hpp"
#include "imaging/row_levels.hpp"
#include "imaging/row_pool.hpp"

namespace flutterscan::imaging {

/// \brief Raised-cosine weights for extending a row of `width` to `padded` samples.
std::vector<float> periodic_blend(int width, int padded);

/// \brief Fills padded[W..N) from padded[0..W) with the smooth periodic
/// extension: blend[i] carries the row's last value back to its first.
void extend_row_periodically(std::span<float> padded, int width, std::span<const float> blend);

/// \brief For every channel c: extends the loaded row in padded[c] (its first `width`
/// samples) periodically, transforms it and adds filters[c] x spectrum into `sum`
/// (bins complex values, interleaved floats). `spectrum` is scratch.
void filter_and_sum_channels(const RowFft& fft,
                             std::span<const std::vector<std::complex<float>>> filters, int width,
                             std::span<const float> blend, std::span<AlignedFloats> padded,
                             AlignedFloats& spectrum, float* sum);

/// \brief One channel's part of the problem: PSF taps (e- per unit reflectance) and noise variance.
struct ChannelPsf {
  std::vector<double> taps;
  double noise_variance = 1;
};

/// \brief A joint Wiener filter for rows of one width, plans and filters made
/// once, reusable for any number of frames.
class JointWiener {
 public:
  /// \brief `lambda` weights the gradient prior (inverse latent gradient variance).
  JointWiener(std::span<const ChannelPsf> channels, int width, double lambda,
              PlanEffort effort = PlanEffort::kEstimate);
  /// \brief Any filter of this shape (the latent's spectrum is sum_c T_c Y_c) from
  /// its channels' transfer functions T_c on bins 0..n/2 of an n-point row FFT (n
  /// even, at least width plus the longest PSF, as row_fft_length() gives); each
  /// must be the spectrum of a real impulse response.
  JointWiener(std::span<const std::vector<std::complex<double>>> transfer, int n, int width,
              PlanEffort effort = PlanEffort::kEstimate);

  int width() const { return width_; }
  int channel_count() const { return static_cast<int>(filters_.size()); }
  int padded_length() const { return fft_.length(); }

  /// \brief Writes row `y` of every channel (electrons, width() samples) into `rows[c]`.
  using RowLoader = std::function<void(int y, std::span<const std::span<float>> rows)>;

  /// \brief Deconvolves `height` rows fetched by `load` into `out` (width() x height,
  /// allocated by the caller) on `pool`. Buffers are made on the first call for a
  /// pool size and reused: steady-state frames allocate nothing.
  void deconvolve(const RowLoader& load, int height, Plane& out, RowPool& pool);

  /// \brief Deconvolves whole planes (rows in the motion frame) on `threads`
  /// threads; `levels`, when they fit the planes (MotionFrame::row_levels), spare
  /// the flat-row test reading the rows.
  Plane deconvolve(std::span<const Plane> channels, int threads, const RowLevels* levels = nullptr);

  /// \brief From now on, rows that carry only noise are filled, not transformed
  /// (the header's "Flat rows"): channel c's noise variance at a row mean m e-
  /// is base_variance[c] + m (read noise and quantisation, then shot noise). A
  /// row is flat when, in every channel and every stretch of kFlatRowStretch
  /// samples, the mean square about the row's mean is at most kFlatRowSigmas
  /// standard errors above that.
  void skip_flat_rows(std::vector<double> base_variance);
  /// \brief How many rows the last deconvolve() found flat.
  int flat_rows() const { return flat_rows_; }

 private:
  /// One thread's buffers: each channel's two rows as loaded (width() samples),
  /// then the pair as one complex row (N complex values, interleaved floats), its
  /// spectrum, the channels' filtered sum and its inverse.
  struct Scratch {
    std::vector<AlignedFloats> first, second;
    std::vector<std::span<float>> first_rows, second_rows;
    AlignedFloats pair, spectrum, sum, out;
    int flat_rows = 0;  ///< rows this scratch found flat (skip_flat_rows())
  };
  Scratch make_scratch() const;
  /// The rows loaded in scratch.first and .second, deconvolved into `a` and `b`
  /// (`b` empty: there is no second row).
  void deconvolve_pair(Scratch& scratch, std::span<float> a, std::span<float> b) const;

  int width_;
  RowPairFft fft_;
  /// T_c / N on all N bins (Hermitian), per channel, interleaved complex (joint
  /// Wiener: T_c = conj(G_c) / v_c / D).
  std::vector<AlignedFloats> filters_;
  std::vector<float> blend_;
  std::vector<Scratch> workers_;
  std::vector<double> flat_base_variance_;  ///< empty: every row transformed
  std::vector<float> dc_gains_;             ///< latent of a constant row per e- of channel c
  int flat_rows_ = 0;

  /// Fills `out` with the latent of a flat row and says so; level_of(c) is the
  /// row's level in channel c (row_level()).
  template <typename LevelOf>
  bool fill_if_flat(const LevelOf& level_of, std::span<float> out) const;
  /// Deconvolves `height` rows: load_unless_flat(y, rows, out.row(y)) fills a
  /// flat row's output and returns true, or loads the row into `rows`.
  template <typename LoadUnlessFlat>
  void deconvolve_rows(const LoadUnlessFlat& load_unless_flat, int height, Plane& out,
                       RowPool& pool);
};

/// \brief Standard errors of a noise-only stretch's mean square above its
/// expected value that a stretch (kFlatRowStretch samples, row_levels.hpp) may
/// reach and still count as flat (four: a stretch of noise alone passes it
/// about once in 4000, so about one 1920-px RGB row of noise in a hundred is
/// deconvolved anyway).
inline constexpr double kFlatRowSigmas = 4;

/// \brief A row loader reading row y of each plane of `channels` (motion frame).
JointWiener::RowLoader plane_row_loader(std::span<const Plane> channels);

/// \brief P(w), the Wiener prior's weight at angular frequency w (radians per
/// pixel): twice the latent's gradient power 2 - 2 cos w (an edge seen through
/// the box aperture spreads over two pixels), divided by sinc^4(w / 2 pi).
/// The latent is the scene averaged over each pixel's box aperture, and sharp
/// print finer than a pixel reaches the frame folded back near the Nyquist
/// frequency, where the box-aperture PSFs all vanish: the 1 / sinc^4 keeps that
/// part from being amplified (measured: with the plain gradient prior joint Wiener read
/// none of the simulator's 3000 e- Code 128 frames rendered finer than the pixels).
double label_prior_power(double w);

/// \brief Spectrum of `taps` on the bins of an n-point real FFT.
std::vector<std::complex<double>> psf_spectrum(std::span<const double> taps, int n);

}  // namespace flutterscan::imaging
