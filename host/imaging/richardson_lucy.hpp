#pragma once
// Joint Richardson-Lucy along rows: the maximum-likelihood deconvolution of
// MATLAB's deconvlucy, extended to several channels that observe one latent
// image through different PSFs:
//   x <- x * sum_c G_c^T[(y_c + s) / (G_c x + s)] / sum_c G_c^T 1,
// with s = the read-noise variance, which makes Gaussian read noise an
// approximately Poisson offset and keeps the ratios finite (negative electrons
// after black subtraction are allowed down to -s).
//
// Borders: the latent row is longer than the observed one by K - 1 pixels on
// the left (light that entered the frame during the exposure), convolutions
// are linear (zero-padded FFTs, no wrap-around) and the normaliser counts only
// observed pixels, so nothing rings at the edges. Output column n is the
// latent at column n.
//
// Biggs-Andrews acceleration (deconvlucy's default) extrapolates along the
// last two steps; damping (deconvlucy's DAMPAR) leaves pixels whose residual is
// within `damping` standard deviations nearly unchanged.

#include <span>
#include <vector>

#include "imaging/image.hpp"
#include "imaging/joint_wiener.hpp"
#include "imaging/row_pool.hpp"

namespace flutterscan::imaging {

struct RichardsonLucySettings {
  int iterations = 20;
  bool accelerate = true;
  double damping = 0;  ///< 0 = off; in noise standard deviations
};

class RichardsonLucy {
 public:
  RichardsonLucy(std::span<const ChannelPsf> channels, int width, double read_variance,
                 const RichardsonLucySettings& settings, PlanEffort effort = PlanEffort::kEstimate);

  /// \brief Deconvolves whole planes (electrons, motion frame) on `threads` threads.
  Plane deconvolve(std::span<const Plane> channels, int threads);

  /// \brief Deconvolves `channels` into `out` (width() x height, allocated by the
  /// caller) on `pool`. Worker buffers are made on the first call for a pool size
  /// and reused: steady-state frames allocate nothing.
  void deconvolve(std::span<const Plane> channels, Plane& out, RowPool& pool);

 private:
  struct Scratch {
    std::vector<AlignedFloats> observed;       ///< per channel: the row plus the offset
    std::vector<std::span<const float>> rows;  ///< per channel: the row being solved
    AlignedFloats x, x_previous, ahead;        ///< latent rows (extended length)
    AlignedFloats step, step_before;           ///< the last two RL steps, for acceleration
    AlignedFloats real;                        ///< padded real buffer
    AlignedFloats spectrum, work, sum;         ///< half-complex buffers
  };
  Scratch make_scratch(std::size_t channels) const;
  void deconvolve_row(std::span<const std::span<const float>> rows, std::span<float> out,
                      Scratch& scratch) const;

  int width_;
  int taps_;      ///< K: longest PSF
  int extended_;  ///< latent row length W + K - 1
  RowFft fft_;
  double offset_;
  RichardsonLucySettings settings_;
  std::vector<std::vector<std::complex<float>>> spectra_;  ///< G_c / N
  std::vector<float> inverse_normaliser_;  ///< 1 / sum_c G_c^T 1 per latent pixel (0 where unseen)
  double white_gain_ = 1;                  ///< sum over channels and taps
  std::vector<Scratch> workers_;
};

}  // namespace flutterscan::imaging
