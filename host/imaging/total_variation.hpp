#pragma once
// Edge-preserving joint deconvolution along rows ("tv"): the joint Wiener
// problem of joint_wiener.hpp with its quadratic smoothness prior replaced by
// one that keeps the sharp edges of printed labels.
//
// Model (reflectance x, channel c observes y_c = g_c * x + noise of variance v_c):
//   minimise  sum_c |g_c * x - y_c|^2 / (2 v_c)
//             + a_along |D_along x|_1 + a_across |D_across x|_1    (anisotropic TV)
//   subject to 0 <= x <= 1                                        (reflectance)
// D_along is the forward difference along the motion (the row), D_across the
// one across it (between rows). The data term carries the noise model: v_c is
// channel_noise_variance at the frame's mean signal, g_c channel_psf in e- per
// unit reflectance, so the weights a are per unit reflectance gradient.
// Barcodes are constant across the bars, so a_across > a_along.
// The weights follow the noise: a_along = kappa / sigma, where sigma^2 is the
// mean per-pixel posterior variance of the joint Wiener model of the same
// data (mean over frequencies of 1 / (sum_c |G_c|^2 / v_c + lambda |D|^2)),
// so the prior's soft threshold keeps one size in units of the noise the
// estimate must remove, whatever the light level and the code's conditioning.
// A fixed weight (a Laplacian prior of fixed scale) over-smooths in dim light
// and lets noise through in bright light: on the label scenes its best value
// grew from about 4 at 300 e- to 26 at 10000 e- for one code, and differed by
// 1.6x between codes at one light level, while kappa = 0.5 was within about
// 0.5 dB of the best weight for both codes at every level.
// EdgePrior::kL0Gradient replaces both |.|_1 by the count of non-zero
// gradients (a two-tone / piecewise-constant prior in the spirit of Pan et
// al. 2014), solved by half-quadratic splitting with a growing penalty.
//
// Solver: over-relaxed ADMM (relaxation 1.8) with splits z_along = D_along x,
// z_across = D_across x, w = x. The x-update is solved exactly: its matrix,
// the data term plus
// rho_along D_along^T D_along + rho_across D_across^T D_across + rho_box I,
// is the same for every row (one PSF per channel) and circulant along it, so
// in each row's FFT it falls apart into one real symmetric tridiagonal system
// per frequency bin, across the rows (the across-row differences, Neumann at
// the first and last row). Its LDL^T pivots depend only on the bin and the row
// and are made once per frame height (per iteration for L0, whose penalty
// grows); each iteration then is the rows' forward FFTs, one sweep down and
// one back up the rows per bin (vectorised across the bins), and the rows'
// inverse FFTs. The data part of the right-hand side, sum_c conj(G_c) Y_c / v_c,
// is computed once per frame. z-updates are soft thresholds (hard for L0), w
// is the clip to [0, 1]. Each iteration is two passes over the frame on the
// RowPool: the sweeps (bins split between the threads), then the rows: each
// row's inverse FFT, its splits, the edge above it and the next iteration's
// right-hand side one row behind, while the rows are in cache. Rows 2k and
// 2k + 1 go through both FFTs together as one complex row (RowPairFft, as in
// joint_wiener.hpp), on any number of threads (the threads' shares start at
// even rows), so the result does not depend on the thread count.
// An earlier solver linearised the across-row term instead (a proximal term
// 4 rho_across I, which kept the update row-separable but damped every step),
// without relaxation and with thresholds of 2 sigma: it needed 40 iterations
// for what this one reaches in 15 (docs/benchmarks.md, build/bin/tv_iterations).
//
// Warm start: the joint Wiener solution of the same periodic problem
// (lambda = Settings::wiener_lambda), computed from the data spectra that the
// solver needs anyway (one extra inverse FFT per row), so the whole padded
// row starts from it. A caller's own warm start plane may be given instead.
//
// Borders: as joint Wiener, periodic. Each observed row (width W) is extended
// to the FFT length N >= W + K with the raised-cosine blend back to its first
// value, and the latent is a periodic row of N samples: its last K - 1
// samples hold the scene that entered the frame from the left during the
// exposure, the rest of the gap is latent under the blended (made-up)
// observation. Along-row differences wrap; across-row differences are
// Neumann (none beyond the first and last row). Output column n is the latent
// at column n (registered at the start of slot 0), clipped to [0, 1].
//
// Parameters: the noise enters through v_c and sigma. kappa (0.5), the across
// to along ratio (4), the ADMM thresholds (0.8 sigma since issue 14, 2 sigma
// before; rho = a / threshold), the box penalty (100) and the iterations (15;
// 40 before) were fixed once from the Code 128 / EAN-13 / QR / Data Matrix /
// text label scenes (640x360, 52 px blur, found-mse, found-joint and
// Raskar-white, 300 to 10000 e-) and are constants, not per-image tuning.
// Larger across ratios score still higher on those axis-aligned synthetic
// labels but flatten rotated ones. L0 (fixed weights 2 and 8) scores 3 dB
// above TV on axis-aligned labels but 4 dB below it on a 7-degree rotated
// one, so TV is the default.

#include <span>
#include <utility>
#include <vector>

#include "imaging/image.hpp"
#include "imaging/joint_wiener.hpp"
#include "imaging/row_fft.hpp"
#include "imaging/row_pool.hpp"

namespace flutterscan::imaging {

/// \brief The gradient prior: |gradient| (convex TV) or the count of non-zero gradients (L0).
enum class EdgePrior { kTotalVariation, kL0Gradient };

/// \brief tv's kappa where a frame is deblurred to be read (the session's tv,
/// whole frame or window): the weight that reads most, not the default (the best
/// PSNR). Kappa 0.25-0.35 read more than 0.5 on real print at every light level
/// and as much or more on the synthetic labels, 0.18 less (docs/algorithms.md, "tv").
inline constexpr double kReadingWeightPerNoise = 0.3;

/// \brief Solver settings. The defaults are the TV ones; l0_settings() gives the L0 ones.
struct TotalVariationSettings {
  EdgePrior prior = EdgePrior::kTotalVariation;
  int iterations = 15;
  /// TV: kappa; when > 0 the solver sets weight_along = kappa / sigma (sigma: the
  /// joint Wiener model's per-pixel posterior standard deviation, see above) and
  /// weight_across = across_ratio * weight_along. 0: the weights below as given.
  double weight_per_noise = 0.5;
  double across_ratio = 4.0;  ///< a_across / a_along (labels are constant across the bars)
  /// a_along: weight per unit reflectance gradient (L0: weight per non-zero gradient).
  double weight_along = 8.0;
  double weight_across = 32.0;  ///< a_across
  /// TV with weight_per_noise > 0: the ADMM splits' soft threshold (a / rho) in units
  /// of sigma; it sets only how fast ADMM converges, not where. 0.8 with relaxation
  /// 1.8: 15 iterations within 0.16 dB of 160 on average from 300 to 10000 e- on the
  /// label scenes, 0.6 dB on the Data Matrix label, which converges last (picked from
  /// 0.3-1.2 at 3000 e-: 0.5 was 0.3 dB lower there at 15 iterations, 1.0 on a par
  /// there but 0.03 dB lower on average; a fixed 0.05 lost 3 dB at 300 e-).
  double threshold_per_noise = 0.8;
  /// TV: a / rho, the soft threshold of the ADMM splits (reflectance gradient).
  /// L0: the first hard threshold; it shrinks as the penalty grows.
  double threshold_along = 0.05;
  double threshold_across = 0.05;
  double box_penalty = 100.0;  ///< rho of the 0 <= x <= 1 split
  /// ADMM over-relaxation alpha (1: none): each split is updated from alpha D x +
  /// (1 - alpha) z_previous rather than D x (Eckstein and Bertsekas 1992). 1.8 needs
  /// about half the iterations of 1.0 for the same PSNR on the label scenes.
  double relaxation = 1.8;
  /// L0 only: the penalty grows by this factor per iteration (half-quadratic continuation).
  double l0_growth = 1.15;
  /// L0 only: the penalty stops growing at this multiple of its first value. Beyond
  /// about 1e12 the float right-hand side of the x-update (penalty times the splits)
  /// swamps the data term in the low frequencies, and the estimate falls apart.
  double l0_most_growth = 1e6;
  double wiener_lambda = 20.0;  ///< the warm start's gradient prior (1 / kLabelGradientVariance)
};

/// \brief The L0-gradient settings fixed from the label scenes (weights 2 and 8,
/// first threshold 0.3, penalty growth 1.7 per iteration: with the exact x-update,
/// 15 iterations scored 0.5-1.8 dB above 40 of the earlier solver at its growth of
/// 1.25, which now needed 40 iterations, from 300 to 10000 e-).
TotalVariationSettings l0_settings();

/// \brief Joint edge-preserving deconvolution for rows of one width: plans,
/// filters and frame buffers made once and reused (steady-state frames of one
/// height allocate nothing).
class TotalVariation {
 public:
  /// \brief `channels`: each channel's PSF (e- per unit reflectance) and noise variance.
  TotalVariation(std::span<const ChannelPsf> channels, int width,
                 const TotalVariationSettings& settings, PlanEffort effort = PlanEffort::kEstimate);

  /// \brief Row width (samples along the motion) this solver was made for.
  int width() const { return width_; }
  /// \brief N: the periodic latent row length (the row FFT length).
  int padded_length() const { return fft_.length(); }

  using RowLoader = JointWiener::RowLoader;

  /// \brief Deconvolves `height` rows fetched by `load` (electrons, motion frame)
  /// into `out` (width() x height, allocated by the caller) on `pool`. `warm_start`
  /// (width() x height reflectance) is the first estimate; empty = the joint
  /// Wiener solution made here.
  void deconvolve(const RowLoader& load, int height, const Plane& warm_start, Plane& out,
                  RowPool& pool);

  /// \brief Deconvolves whole planes (electrons, rows along the motion) on `threads` threads.
  Plane deconvolve(std::span<const Plane> channels, const Plane& warm_start, int threads);

 private:
  struct Scratch {
    std::vector<AlignedFloats> padded;   ///< per channel, N
    std::vector<std::span<float>> rows;  ///< first width() samples of each
    AlignedFloats real;                  ///< N
    AlignedFloats spectrum;              ///< bins complex
    AlignedFloats pair, pair_spectrum;   ///< N complex each: two rows as one (RowPairFft)
  };
  struct Penalties {
    float along, across, box;
    bool operator==(const Penalties&) const = default;
  };
  /// One iteration's penalties and thresholds.
  struct Step {
    float rho_along, threshold_along;
    float rho_across, threshold_across;
    float rho_box;
  };
  /// Step `k` (1-based) of `settings`: constant for ADMM, growing for L0.
  static Step step_of(const TotalVariationSettings& settings, int k);
  void prepare(int height, int threads);
  void load_data(int y, const RowLoader& load, Scratch& s, bool wiener_start);
  void split_row(int y, float threshold, bool restart);
  void split_edge(int edge, float threshold, bool restart);
  /// Row y's part of the x-update's right-hand side that the splits make, into `real` (N).
  void right_hand_side(int y, const Penalties& rho, float* real) const;
  /// Row y's right-hand side transformed, with the data part, into its spectra_ row.
  /// Rows 2k and 2k + 1 are transformed together (RowPairFft), whichever comes
  /// second; the first waits in its spectra_ row (rhs_waiting_). A row without a
  /// partner (the last of an odd height) goes alone.
  void transform_row(int y, Scratch& s, const Penalties& rho);
  /// Row y of spectra_ (spectrum_stride_ floats: bins complex, or a waiting right-hand side).
  float* spectrum_row(int y) const {
    return spectra_.data() + static_cast<std::size_t>(y) * spectrum_stride_;
  }
  /// Rows y and y + 1 (y even) of x from their solved spectra, as one inverse.
  void invert_pair(int y, Scratch& s);
  /// Row y of x is this iteration's: its along and box splits (`threshold_along`),
  /// then the `next` iteration's split of the edge above it (rows y - 1 and y are
  /// both done) and right-hand side of the row above (it waited for that edge).
  /// `first`: the first row of this worker's share, whose edge above and
  /// right-hand side wait for finish_seams().
  void finish_row(int y, int first, Scratch& s, float threshold_along, bool restart,
                  const Step& next);
  /// What finish_row() left at the shares' seams: the edges between shares, then
  /// the right-hand sides of each share's first and last rows.
  void finish_seams(std::span<const std::pair<int, int>> shares, const Step& next, bool restart);
  void factor_across(const Penalties& rho);
  void solve_across(int first_bin, int last_bin, float rho_across);

  int width_;
  RowFft fft_;
  RowPairFft pair_fft_;
  TotalVariationSettings settings_;
  std::vector<std::vector<std::complex<float>>> filters_;  ///< conj(G_c) / v_c
  std::vector<double> data_power_;                         ///< sum_c |G_c|^2 / v_c per bin
  std::vector<float> wiener_inverse_;                      ///< 1 / ((A + lambda P) N)
  std::vector<float> blend_;
  std::vector<Scratch> workers_;
  int height_ = 0;
  std::size_t stride_ = 0;           ///< N
  std::size_t spectrum_stride_ = 0;  ///< 2 * bins rounded up to 64 bytes (aligned rows)
  // Frame state, N x height each (row y at y * N).
  AlignedFloats data_;  ///< sum_c conj(G_c) Y_c / v_c, bins complex per row (stride 2 * bins)
  // Each split keeps its scaled dual u and s = z - u (TV), or z (L0); s_across per edge.
  AlignedFloats x_, dual_along_, split_along_, dual_box_, split_box_, dual_across_, split_across_;
  AlignedFloats spectra_;          ///< the x-update's right-hand side, then its solution, per row
  AlignedFloats pivots_;           ///< 1 / the tridiagonal pivots, bins per row
  std::vector<char> rhs_waiting_;  ///< per row: its right-hand side waits for its pair's
  Penalties factored_{0, 0, 0};    ///< the penalties pivots_ hold (0: none yet)
};

}  // namespace flutterscan::imaging
