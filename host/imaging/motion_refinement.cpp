#include "imaging/motion_refinement.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <limits>
#include <numeric>
#include <vector>

#include "imaging/exposure_timeline.hpp"
#include "imaging/golden_section.hpp"
#include "imaging/motion_frame.hpp"
#include "imaging/row_fft.hpp"

namespace flutterscan::imaging {
namespace {

constexpr int kBlocks = 8;
/// The most channels a capture model has (capture_model_problem: 1 or 3).
constexpr std::size_t kMaxChannels = 3;
/// Below this significance the residual barely depends on the blur: no edges
/// along the motion (MotionRefinement::significance).
constexpr double kMinimumSignificance = 20;
/// The two-parameter motion is kept when the constant-speed residual per sample
/// is above this (the noise gives about 1) ...
constexpr double kAboveNoise = 1.05;
/// ... and the accelerating motion lowers the residual by at least this share.
constexpr double kAccelerationGain = 0.05;
/// Speed ratios searched: exp(+-kLogRatioRange).
constexpr double kLogRatioRange = 0.8;  // 0.45 .. 2.2
/// The wandering motion: offsets at the knots of this many equal-time blocks (at
/// 52 slots about 3 per block: a belt's per-slot jitter leaves about a quarter
/// of its displacement error between the knots, and finer knots found local
/// minima of the residual rather than the belt's motion), ...
constexpr int kWanderBlocks = 16;
/// ... the prior's spread of one slot's travel around the smooth motion's, in
/// slots (twice the jitter the stability study's 0.2 point has), ...
constexpr double kJitterPrior = 0.4;
/// ... at most this many damped Gauss-Newton steps per level, the taps
/// differenced over this much motion, ...
constexpr int kWanderIterations = 15;
constexpr double kJacobianStepPx = 1e-3;
/// ... stopping when a step lowers the objective (half the residual sum: a log
/// likelihood) by less than this, ...
constexpr double kWanderConverged = 1.0;
/// ... kept when it lowers the residual by this share (a clearer gain than the
/// accelerating motion's: it has many more parameters), and given up after the
/// 4 blocks when they lower it by less than this.
constexpr double kWanderingGain = 0.03;
constexpr double kWanderFirstLevelGain = 0.01;
/// Rows are read in batches, the first of this many; ...
constexpr int kFirstRows = 32;
/// ... then as many as the standard error of the first says bring it below this
/// (px: 2.5 times below the 0.05 px rms the refinement is held to; the error
/// falls as 1 / sqrt(rows)), ...
constexpr double kEnoughPrecisionPx = 0.02;
/// ... unless the frame cannot show edges with every row read: the significance
/// grows at most as the square root of the rows (they are read edgiest first),
/// so a frame whose significance, scaled by sqrt(all rows / rows read), stays
/// short of kMinimumSignificance, or whose last batch lowered it, stops.

double square(double v) {
  return v * v;
}

/// Solves m x = b in place (b becomes x) for a symmetric positive definite
/// n x n matrix m (row-major; overwritten) by Cholesky; false if m is not
/// positive definite.
bool solve_positive_definite(std::vector<double>& m, std::vector<double>& b) {
  const std::size_t n = b.size();
  for (std::size_t j = 0; j < n; ++j) {
    double diagonal = m[j * n + j];
    for (std::size_t k = 0; k < j; ++k) diagonal -= square(m[j * n + k]);
    if (!(diagonal > 0)) return false;
    const double root = std::sqrt(diagonal);
    m[j * n + j] = root;
    for (std::size_t i = j + 1; i < n; ++i) {
      double sum = m[i * n + j];
      for (std::size_t k = 0; k < j; ++k) sum -= m[i * n + k] * m[j * n + k];
      m[i * n + j] = sum / root;
    }
  }
  for (std::size_t i = 0; i < n; ++i) {  // L y = b
    for (std::size_t k = 0; k < i; ++k) b[i] -= m[i * n + k] * b[k];
    b[i] /= m[i * n + i];
  }
  for (std::size_t i = n; i-- > 0;) {  // L' x = y
    for (std::size_t k = i + 1; k < n; ++k) b[i] -= m[k * n + i] * b[k];
    b[i] /= m[i * n + i];
  }
  return true;
}

/// `theta` (a blur, then block offsets at the knots between equal-time blocks,
/// 0 at both ends) with its offsets resampled at the knots of `blocks` blocks:
/// the same piecewise-linear displacement, read at other knots.
std::vector<double> resampled(const std::vector<double>& theta, int blocks) {
  const std::size_t old_knots = theta.size() - 1;
  const auto offset_at = [&](std::size_t knot) {  // 0 at both ends
    return knot == 0 || knot > old_knots ? 0.0 : theta[knot];
  };
  std::vector<double> out = {theta[0]};
  for (int i = 1; i < blocks; ++i) {
    const double position = static_cast<double>(i) / blocks * static_cast<double>(old_knots + 1);
    const auto knot = static_cast<std::size_t>(position);
    const double f = position - static_cast<double>(knot);
    out.push_back((1 - f) * offset_at(knot) + f * offset_at(knot + 1));
  }
  return out;
}

/// One differenced motion row per channel, all of one length.
using RowSet = std::vector<std::vector<float>>;

/// The motion rows with the most edge energy along the motion: every
/// `stride`-th row scored, the `count` best returned in order of energy (best
/// first).
std::vector<int> edgiest_rows(const Plane& plane, int count) {
  const int stride = std::max(1, plane.height / (2 * count));
  std::vector<std::pair<double, int>> scored;
  for (int r = 0; r < plane.height; r += stride) {
    const float* row = plane.row(r).data();
    const auto width = static_cast<std::size_t>(plane.width);
    float sum = 0;
#pragma omp simd reduction(+ : sum)
    for (std::size_t n = 1; n < width; ++n) sum += std::abs(row[n] - row[n - 1]);
    scored.emplace_back(sum, r);
  }
  const auto keep = std::min<std::size_t>(scored.size(), static_cast<std::size_t>(count));
  std::partial_sort(scored.begin(), scored.begin() + static_cast<std::ptrdiff_t>(keep),
                    scored.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  std::vector<int> out;
  for (std::size_t i = 0; i < keep; ++i) out.push_back(scored[i].second);
  return out;
}

/// The stretch [first, last] of differenced samples along the motion where the
/// rows `rows` of `plane` have edges (columns whose summed |difference| is well
/// above the median column's, i.e. the labels), widened by `taps` samples on
/// either side and to at least 4 `taps`: the rest is belt, whose samples add
/// noise but no information, and shorter rows make every FFT cheaper. The whole
/// differenced row when nothing stands out.
std::pair<std::size_t, std::size_t> edge_stretch(const Plane& plane, const std::vector<int>& rows,
                                                 int taps) {
  const auto width = static_cast<std::size_t>(plane.width) - 1;  // differenced
  std::vector<float> energy(width, 0.0f);
  for (int r : rows) {
    const float* d = plane.row(r).data();
#pragma omp simd
    for (std::size_t n = 0; n < width; ++n) energy[n] += std::abs(d[n + 1] - d[n]);
  }
  std::vector<float> sorted = energy;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(width / 2),
                   sorted.end());
  const float floor = 3 * sorted[width / 2];
  std::size_t lo = width, hi = 0;
  for (std::size_t n = 0; n < width; ++n)
    if (energy[n] > floor) lo = std::min(lo, n), hi = n;
  if (lo > hi) return {0, width - 1};  // nothing stands out: the whole rows
  const auto margin = static_cast<std::size_t>(taps);
  lo = lo > margin ? lo - margin : 0;
  hi = std::min(width - 1, hi + margin);
  const std::size_t least = 4 * margin;
  while (hi - lo + 1 < least && (lo > 0 || hi + 1 < width)) {
    if (lo > 0) --lo;
    if (hi + 1 < width) ++hi;
  }
  return {lo, hi};
}

/// The residual of every candidate motion as quadratic forms in its taps
/// (motion_refinement.hpp): G_ab per block of rows and pair of channels, built
/// up as rows are added.
class ResidualForms {
 public:
  /// Rows of `width` differenced samples, `channels` channels, PSFs of `taps` taps.
  ResidualForms(int taps, int channels, int width)
      : taps_(taps),
        channels_(channels),
        valid_(width - (taps - 1)),
        fft_(thread_row_fft(row_fft_length(width + taps))) {
    const auto p = static_cast<std::size_t>(taps);
    const std::size_t slots = kBlocks * pairs();
    // One aligned buffer per spectrum: FFTW's plans want the alignment they were made with.
    for (std::size_t i = 0; i < slots; ++i) cross_.emplace_back(2 * bins());
    for (auto& s : cross_) std::fill(s.data(), s.data() + 2 * bins(), 0.0f);
    base_ab_.assign(slots, std::vector<double>(p, 0.0));
    base_ba_.assign(slots, std::vector<double>(p, 0.0));
    ends_.assign(slots, std::vector<double>(p * p, 0.0));
    gram_.assign(slots + pairs(), std::vector<double>(p * p, 0.0));
    rows_in_block_.assign(kBlocks + 1, 0);
  }

  /// Adds rows[first..last) to the forms; the block of row r is r % kBlocks.
  void add(const std::vector<RowSet>& rows, std::size_t first, std::size_t last) {
    const auto n = static_cast<std::size_t>(fft_.length());
    const auto p = static_cast<std::size_t>(taps_);
    AlignedFloats padded(n);
    std::vector<AlignedFloats> spectra;
    for (int c = 0; c < channels_; ++c) spectra.emplace_back(2 * bins());
    std::vector<double> head_b(p), tail_b(p);
    for (std::size_t r = first; r < last; ++r) {
      const std::size_t block = r % kBlocks;
      ++rows_in_block_[block];
      ++rows_in_block_[kBlocks];
      for (int c = 0; c < channels_; ++c) {
        const auto& row = rows[r][static_cast<std::size_t>(c)];
        std::copy(row.begin(), row.end(), padded.data());
        std::fill(padded.data() + row.size(), padded.data() + n, 0.0f);
        fft_.forward(padded.data(), spectra[static_cast<std::size_t>(c)].complex());
      }
      std::size_t q = 0;
      for (int a = 0; a < channels_; ++a)
        for (int b = a; b < channels_; ++b, ++q) {
          const std::size_t slot = block * pairs() + q;
          // sum_n a[n] b[n - k] has the spectrum A conj(B).
          accumulate_spectra(spectra[static_cast<std::size_t>(b)].data(),
                             spectra[static_cast<std::size_t>(a)].data(), cross_[slot].data(),
                             bins(), true);
          const auto& ra = rows[r][static_cast<std::size_t>(a)];
          const auto& rb = rows[r][static_cast<std::size_t>(b)];
          const std::size_t head = p - 1;  // F, the first valid sample
          // G[0][j] lacks sum_{n=j}^{F-1} a[n] b[n-j]; G[i][0] lacks the mirror.
          for (std::size_t j = 0; j < head; ++j) {
            double head_ab = 0, head_ba = 0;
            const float* a_from = ra.data() + j;
            const float* b_from = rb.data() + j;
            const std::size_t count = head - j;
#pragma omp simd reduction(+ : head_ab, head_ba)
            for (std::size_t k = 0; k < count; ++k) {
              head_ab += static_cast<double>(a_from[k]) * rb[k];
              head_ba += static_cast<double>(b_from[k]) * ra[k];
            }
            base_ab_[slot][j] -= head_ab;
            base_ba_[slot][j] -= head_ba;
          }
          // G[i+1][j+1] = G[i][j] + a[F-1-i] b[F-1-j] - a[W-1-i] b[W-1-j]: the
          // ends of b reversed into contiguous scratch, so the update vectorises.
          const std::size_t tail = ra.size() - 1;
          for (std::size_t j = 0; j + 1 < p; ++j) {
            head_b[j] = rb[head - 1 - j];
            tail_b[j] = rb[tail - j];
          }
          auto& e = ends_[slot];
          const std::size_t inner = p - 1;
          for (std::size_t i = 0; i < inner; ++i) {
            const double head_a = ra[head - 1 - i], tail_a = ra[tail - i];
            double* out = e.data() + i * p;
            const double* hb = head_b.data();
            const double* tb = tail_b.data();
#pragma omp simd
            for (std::size_t j = 0; j < inner; ++j) out[j] += head_a * hb[j] - tail_a * tb[j];
          }
        }
    }
    update_grams();
  }

  int rows() const {
    return rows_in_block_[kBlocks];
  }

  struct Sum {
    double value = 0;         ///< of e^2 / var(e) over the valid samples
    std::size_t samples = 0;  ///< valid samples summed
    double mean() const { return samples > 0 ? value / static_cast<double>(samples) : 0; }
  };

  /// The residual of per-channel taps (each `taps` long) over block `block`
  /// (-1: all), each pair's samples weighted by 1 / var(e) from `variances`.
  Sum operator()(const std::vector<std::vector<double>>& taps, const std::vector<double>& variances,
                 int block) const {
    const auto p = static_cast<std::size_t>(taps_);
    const auto shape = tap_shape(taps);
    Sum total;
    const auto k = static_cast<std::size_t>(block < 0 ? kBlocks : block);  // totals after blocks
    const auto rows = static_cast<std::size_t>(rows_in_block_[k]);
    for (int c = 0; c < channels_; ++c)
      for (int d = c + 1; d < channels_; ++d) {
        const auto uc = static_cast<std::size_t>(c), ud = static_cast<std::size_t>(d);
        const double variance = pair_variance(shape, variances, uc, ud);
        if (!(variance > 0)) continue;
        const auto& g_cc = gram_[k * pairs() + pair_index(c, c)];
        const auto& g_dd = gram_[k * pairs() + pair_index(d, d)];
        const auto& g_cd = gram_[k * pairs() + pair_index(c, d)];
        const auto& hc = taps[uc];
        const auto& hd = taps[ud];
        const std::size_t sc = shape.support[uc], sd = shape.support[ud];
        const double energy = form(hd, sd, g_cc, hd, sd, p) + form(hc, sc, g_dd, hc, sc, p) -
                              2 * form(hd, sd, g_cd, hc, sc, p);
        total.value += energy / variance;
        total.samples += rows * static_cast<std::size_t>(valid_);
      }
    return total;
  }

  /// The matrix A of the residual over every row as a quadratic form h' A h of
  /// all channels' taps stacked (channel c's tap i at c * taps + i; row-major),
  /// with the pairs' weights 1 / var(e) taken at `taps`.
  std::vector<double> hessian(const std::vector<std::vector<double>>& taps,
                              const std::vector<double>& variances) const {
    const auto p = static_cast<std::size_t>(taps_);
    const std::size_t n = p * static_cast<std::size_t>(channels_);
    const auto shape = tap_shape(taps);
    std::vector<double> a(n * n, 0.0);
    const auto add = [&](std::size_t row_channel, std::size_t column_channel,
                         const std::vector<double>& g, double weight) {
      for (std::size_t i = 0; i < p; ++i) {
        double* out = a.data() + (row_channel * p + i) * n + column_channel * p;
        const double* in = g.data() + i * p;
#pragma omp simd
        for (std::size_t j = 0; j < p; ++j) out[j] += weight * in[j];
      }
    };
    for (int c = 0; c < channels_; ++c)
      for (int d = c + 1; d < channels_; ++d) {
        const auto uc = static_cast<std::size_t>(c), ud = static_cast<std::size_t>(d);
        const double variance = pair_variance(shape, variances, uc, ud);
        if (!(variance > 0)) continue;
        const double w = 1 / variance;
        // h_d' G_cc h_d + h_c' G_dd h_c - 2 h_d' G_cd h_c: the (d, c) block here,
        // its mirror (c, d) below.
        add(ud, ud, total_gram(c, c), w);
        add(uc, uc, total_gram(d, d), w);
        add(ud, uc, total_gram(c, d), -w);
      }
    for (std::size_t c = 0; c < static_cast<std::size_t>(channels_); ++c)
      for (std::size_t d = c + 1; d < static_cast<std::size_t>(channels_); ++d)
        for (std::size_t i = 0; i < p; ++i)
          for (std::size_t j = 0; j < p; ++j)
            a[(c * p + i) * n + d * p + j] = a[(d * p + j) * n + c * p + i];
    return a;
  }

 private:
  /// Per channel: |difference of h|^2 (the noise of a differenced residual) and
  /// the taps up to the last one that is not 0 (shorter blurs than the longest searched).
  struct TapShape {
    std::array<double, kMaxChannels> power{};
    std::array<std::size_t, kMaxChannels> support{};
  };

  TapShape tap_shape(const std::vector<std::vector<double>>& taps) const {
    const auto p = static_cast<std::size_t>(taps_);
    TapShape shape;
    for (std::size_t c = 0; c < taps.size(); ++c) {
      double sum = 0, previous = 0;
      for (std::size_t i = 0; i < p; ++i) {
        sum += square(taps[c][i] - previous);
        previous = taps[c][i];
        if (previous != 0) shape.support[c] = i + 1;
      }
      shape.power[c] = sum + square(previous);
    }
    return shape;
  }

  /// var(e_cd) per differenced sample.
  static double pair_variance(const TapShape& shape, const std::vector<double>& variances,
                              std::size_t c, std::size_t d) {
    return variances[c] * shape.power[d] + variances[d] * shape.power[c];
  }

  const std::vector<double>& total_gram(int a, int b) const {
    return gram_[kBlocks * pairs() + pair_index(a, b)];
  }

  std::size_t pairs() const {
    return static_cast<std::size_t>(channels_ * (channels_ + 1) / 2);
  }
  std::size_t bins() const {
    return static_cast<std::size_t>(fft_.bins());
  }

  std::size_t pair_index(int a, int b) const {
    // (a, b), a <= b, in the order add() fills them.
    std::size_t q = 0;
    for (int i = 0; i < channels_; ++i)
      for (int j = i; j < channels_; ++j, ++q)
        if (i == a && j == b) return q;
    return q;
  }

  /// The Gram matrices of every block, and their sums, from what add() gathered.
  void update_grams() {
    const auto n = static_cast<std::size_t>(fft_.length());
    const auto p = static_cast<std::size_t>(taps_);
    const double scale = 1.0 / static_cast<double>(n);
    AlignedFloats spectrum(2 * bins()), correlation(n);
    for (std::size_t q = 0; q < pairs(); ++q) std::fill(total(q).begin(), total(q).end(), 0.0);
    for (std::size_t block = 0; block < kBlocks; ++block)
      for (std::size_t q = 0; q < pairs(); ++q) {
        const std::size_t slot = block * pairs() + q;
        std::copy(cross_[slot].data(), cross_[slot].data() + 2 * bins(), spectrum.data());
        fft_.inverse(spectrum.complex(), correlation.data());  // destroys its input
        auto& g = gram_[slot];
        for (std::size_t j = 0; j < p; ++j) {
          g[j] = correlation[j] * scale + base_ab_[slot][j];                // G[0][j]
          g[j * p] = correlation[(n - j) % n] * scale + base_ba_[slot][j];  // G[j][0]
        }
        const auto& e = ends_[slot];
        for (std::size_t i = 1; i < p; ++i)
          for (std::size_t j = 1; j < p; ++j)
            g[i * p + j] = g[(i - 1) * p + j - 1] + e[(i - 1) * p + j - 1];
        auto& sum = total(q);
        for (std::size_t i = 0; i < sum.size(); ++i) sum[i] += g[i];
      }
  }

  std::vector<double>& total(std::size_t q) {
    return gram_[kBlocks * pairs() + q];
  }

  /// x' G y, G P x P row-major, x 0 from entry nx on and y from ny on (the
  /// search's inner loop: vectorised).
  static double form(const std::vector<double>& x, std::size_t nx, const std::vector<double>& g,
                     const std::vector<double>& y, std::size_t ny, std::size_t p) {
    const double* yd = y.data();
    double sum = 0;
    for (std::size_t i = 0; i < nx; ++i) {
      if (x[i] == 0) continue;
      const double* row = g.data() + i * p;
      double inner = 0;
#pragma omp simd reduction(+ : inner)
      for (std::size_t j = 0; j < ny; ++j) inner += row[j] * yd[j];
      sum += x[i] * inner;
    }
    return sum;
  }

  int taps_;
  int channels_;
  int valid_;
  const RowFft& fft_;
  /// Per [block * pairs + pair]: the cross-spectra summed over the block's rows,
  /// and the exact corrections at the rows' ends (G[0][j], G[j][0], the diagonals).
  std::vector<AlignedFloats> cross_;
  std::vector<std::vector<double>> base_ab_, base_ba_, ends_;
  /// [block * pairs + pair], P x P row-major; "block" kBlocks holds the sums over all.
  std::vector<std::vector<double>> gram_;
  std::vector<int> rows_in_block_;  ///< kBlocks + 1 entries, the last all rows
};

/// The blurs the tolerance allows around a given one, and those searched.
struct BlurRange {
  /// The encoder's blur b within the tolerance t of the true one, either way
  /// the tolerance is read (of b or of the truth): b (1 - t) .. b / (1 - t).
  double lo = 0, hi = 0;
  /// Two slots wider (a truth on the tolerance's edge is found, not clipped).
  double search_lo = 0, search_hi = 0;
};

BlurRange blur_range(const CaptureModel& model, double tolerance) {
  const double b = model.blur_px;
  BlurRange r{b * (1 - tolerance), b / (1 - tolerance), 0, 0};
  const double margin = tolerance > 0 ? 2 * b / model.code.length() : 0;
  r.search_lo = std::max(r.lo - margin, r.lo / 2);
  r.search_hi = r.hi + margin;
  return r;
}

/// A candidate motion: total travel, end / start speed, block offsets (capture_model.hpp).
struct Motion {
  double blur = 0;
  double ratio = 1;
  std::vector<double> offsets;
};

/// The search over the motion on the rows `forms` holds (refine_motion()'s
/// steps after reading the rows): blur_px within [lo, hi] at constant speed,
/// the accelerating motion when the residual asks for it, and the standard
/// error; then, on the last rows only, the wandering motion (wander()).
class MotionSearch {
 public:
  MotionSearch(const ResidualForms& forms, const std::vector<double>& variances,
               const CaptureModel& model, const BlurRange& range, int taps)
      : forms_(forms),
        variances_(variances),
        model_(model),
        range_(range),
        lo_(range.search_lo),
        hi_(range.search_hi),
        taps_(taps) {}

  MotionRefinement run(const MotionRefinementOptions& options) const {
    MotionRefinement out;
    out.rows_used = forms_.rows();
    out.blur_px = model_.blur_px;
    out.speed_ratio = model_.speed_ratio;
    // Offsets the model already has (a descriptor's) stay as they are in this search.
    const std::vector<double>& given = model_.block_offsets_px;
    out.block_offsets_px = given;
    const double slot = model_.blur_px / model_.code.length();
    const double start_ratio = model_.speed_ratio;

    // Constant speed (the model's ratio): a grid of one slot (a blur wrong by
    // less than a slot moves no slot by more than one: the residual's basin
    // around the true blur is wider than that), then golden section.
    double best = model_.blur_px;
    std::vector<double> grid;
    if (options.tolerance > 0) {
      const double step = std::max(0.02, slot);
      double best_cost = INFINITY;
      for (double b = lo_; b <= hi_ + 1e-9; b += step) {
        const double c = mean({b, start_ratio, given});
        grid.push_back(c);
        if (c < best_cost) best_cost = c, best = b;
      }
      best = golden_minimum(
          [&](double b) {
            return mean({b, start_ratio, given});
          },
          std::max(lo_, best - step), std::min(hi_, best + step), 0.005 * std::max(1.0, slot));
    }
    out.constant_speed_residual = mean({best, start_ratio, given});
    out.residual_per_sample = out.constant_speed_residual;
    if (grid.empty()) return out;  // tolerance 0: the given motion, checked
    std::nth_element(grid.begin(), grid.begin() + static_cast<std::ptrdiff_t>(grid.size() / 2),
                     grid.end());
    out.contrast = grid[grid.size() / 2] / out.constant_speed_residual - 1;

    // The accelerating motion, when the constant one leaves a residual above the noise.
    double ratio = start_ratio;
    if (options.speed_change && out.contrast > 0 && out.constant_speed_residual > kAboveNoise) {
      // A grid over both (a strong speed change moves the constant-speed blur off
      // the true one, so the ratio cannot be searched at that blur alone) ...
      double log_ratio = 0, best_cost = INFINITY, blur = best;
      const double step = std::max(0.04, 2 * slot);
      for (double x = -kLogRatioRange; x <= kLogRatioRange + 1e-9; x += 0.4)
        for (double b = lo_; b <= hi_ + 1e-9; b += step)
          if (const double c = mean({b, std::exp(x), given}); c < best_cost)
            best_cost = c, log_ratio = x, blur = b;
      // ... then each in turn by golden section.
      for (int pass = 0; pass < 2; ++pass) {
        const double r = std::exp(log_ratio);
        blur = golden_minimum(
            [&](double b) {
              return mean({b, r, given});
            },
            std::max(lo_, blur - 2 * slot), std::min(hi_, blur + 2 * slot),
            0.005 * std::max(1.0, slot));
        log_ratio = golden_minimum(
            [&](double x) {
              return mean({blur, std::exp(x), given});
            },
            std::max(-kLogRatioRange, log_ratio - 0.4), std::min(kLogRatioRange, log_ratio + 0.4),
            0.002);
      }
      const double accelerating = mean({blur, std::exp(log_ratio), given});
      if (accelerating < out.constant_speed_residual * (1 - kAccelerationGain)) {
        out.accelerating = true;
        best = blur;
        ratio = std::exp(log_ratio);
        out.residual_per_sample = accelerating;
      }
    }

    // Edges: the best blur explains the frame better than a typical one by far
    // more than noise could (the residual's spread over the samples is about
    // sqrt(2 / samples) per sample), and the residual curves up around it.
    const Motion motion{best, ratio, given};
    const auto best_taps = taps_of(motion);  // (none if the given offsets went backwards there)
    const double samples =
        best_taps.empty() ? 0.0 : static_cast<double>(forms_(best_taps, variances_, -1).samples);
    out.significance = out.contrast * out.constant_speed_residual * std::sqrt(samples / 2);
    const double error = standard_error(motion);
    out.edges = out.significance >= kMinimumSignificance && std::isfinite(error);
    out.standard_error_px = out.edges ? error : std::numeric_limits<double>::infinity();
    if (!out.edges) {
      out.accelerating = false;
      out.residual_per_sample = out.constant_speed_residual;
      return out;
    }
    out.blur_px = best;
    out.speed_ratio = ratio;
    mark_outside_tolerance(out);
    return out;
  }

  /// The wandering motion (block offsets on top of `out`'s motion: belt
  /// jitter), fitted when `out` leaves a residual above the noise on a frame
  /// with edges and kept when it explains the frame clearly better. Coarse to
  /// fine over 4, 8 and kWanderBlocks blocks, each level by Levenberg-Marquardt
  /// over the blur and the offsets (the residual a quadratic form in the taps,
  /// ResidualForms::hessian, the taps nearly linear in the motion); a prior
  /// holds each slot's travel near the smooth motion's (the directions the
  /// frame barely constrains stay put).
  void wander(MotionRefinement& out) const {
    if (!out.edges || out.residual_per_sample <= kAboveNoise) return;
    const int slots = model_.code.length();
    const double slot = out.blur_px / slots;
    std::vector<double> theta = {out.blur_px};  // the blur, then the offsets
    theta.insert(theta.end(), out.block_offsets_px.begin(), out.block_offsets_px.end());
    const auto motion_of = [&](const std::vector<double>& t) {
      return Motion{t[0], out.speed_ratio, std::vector<double>(t.begin() + 1, t.end())};
    };
    // Coarse to fine (fewer knots first: the residual has fewer local minima
    // there), each level starting from the last one's motion.
    for (const int blocks : {4, 8, kWanderBlocks}) {
      if (blocks > slots) continue;
      theta = resampled(theta, blocks);
      // A block's travel off the smooth motion's (the differences of the offsets,
      // 0 at both ends) spreads as a random walk over its slots.
      const double prior_weight =
          1 / (square(kJitterPrior * slot) * static_cast<double>(slots) / blocks);
      const auto prior = [&](const std::vector<double>& t) {
        double sum = 0, previous = 0;
        for (std::size_t k = 1; k < t.size(); ++k) sum += square(t[k] - previous), previous = t[k];
        return 0.5 * prior_weight * (sum + square(previous));
      };
      const auto objective = [&](const std::vector<double>& t) {
        if (t[0] < lo_ || t[0] > hi_) return std::numeric_limits<double>::infinity();
        const auto taps = taps_of(motion_of(t));
        if (taps.empty()) return std::numeric_limits<double>::infinity();
        return 0.5 * forms_(taps, variances_, -1).value + prior(t);
      };
      double cost = objective(theta);
      // Levenberg-Marquardt: the normal equations at each accepted motion, solved
      // with more damping (a shorter, steeper step) until a step lowers the cost.
      const auto descend = [&] {
        double damping = 1e-3;
        auto equations = normal_equations(theta, motion_of, prior_weight);
        const std::size_t n = theta.size();
        for (int iteration = 0; iteration < kWanderIterations && !equations.first.empty();
             ++iteration) {
          auto damped = equations.first;
          for (std::size_t k = 0; k < n; ++k) damped[k * n + k] *= 1 + damping;
          std::vector<double> step = equations.second;
          for (double& g : step) g = -g;
          if (!solve_positive_definite(damped, step)) break;
          // (A step that would move a slot backwards costs infinity: more damping.)
          std::vector<double> next = theta;
          for (std::size_t k = 0; k < n; ++k) next[k] += step[k];
          const double next_cost = objective(next);
          if (next_cost < cost) {
            const bool converged = cost - next_cost < kWanderConverged;
            theta = std::move(next);
            cost = next_cost;
            damping /= 3;
            if (converged) break;
            equations = normal_equations(theta, motion_of, prior_weight);
          } else {
            damping *= 4;
          }
        }
      };
      // Coarse levels: each knot searched on a grid (the residual along one knot
      // has minima about a slot apart; a Gauss-Newton step finds the nearest), then
      // descent from the best.
      if (blocks <= 8) {
        const double reach = (blocks <= 4 ? 1.5 : 0.75) * std::max(1.0, slot);
        const double step = reach / (blocks <= 4 ? 6 : 3);
        for (std::size_t k = 1; k < theta.size(); ++k) {
          const double centre = theta[k];
          double best = centre;
          for (double v = centre - reach; v <= centre + reach + 1e-9; v += step) {
            auto t = theta;
            t[k] = v;
            if (const double c = objective(t); c < cost) cost = c, best = v;
          }
          theta[k] = best;
        }
      }
      descend();
      // A frame whose residual the coarsest blocks barely move is not jitter (colour
      // print the grey model cannot fit, say): the finer levels would not pay.
      if (blocks == 4 &&
          !(mean(motion_of(theta)) < out.residual_per_sample * (1 - kWanderFirstLevelGain)))
        return;
    }
    const Motion motion = motion_of(theta);
    const double residual = mean(motion);
    if (!(residual < out.residual_per_sample * (1 - kWanderingGain))) return;
    const double error = standard_error(motion);
    if (!std::isfinite(error)) return;
    out.wandering = true;
    out.blur_px = motion.blur;
    out.block_offsets_px = motion.offsets;
    out.residual_per_sample = residual;
    out.standard_error_px = error;
    mark_outside_tolerance(out);
  }

 private:
  /// Gauss-Newton's normal equations N step = -g of wander()'s objective at
  /// `theta` (n x n row-major N, then g; empty for a motion that goes
  /// backwards): the taps' Jacobian by forward differences, J' A J and J' A h
  /// from the residual's matrix A, the prior's tridiagonal terms on the offsets.
  template <typename MotionOf>
  std::pair<std::vector<double>, std::vector<double>> normal_equations(
      const std::vector<double>& theta, const MotionOf& motion_of, double prior_weight) const {
    const std::size_t n = theta.size();
    const auto h = taps_of(motion_of(theta));
    if (h.empty()) return {};
    const std::size_t p = static_cast<std::size_t>(taps_), rows = p * h.size();
    const auto a = forms_.hessian(h, variances_);
    std::vector<double> stacked(rows);
    for (std::size_t c = 0; c < h.size(); ++c)
      std::copy(h[c].begin(), h[c].end(), stacked.begin() + static_cast<std::ptrdiff_t>(c * p));
    // Columns of the Jacobian, each as its non-zero entries.
    std::vector<std::vector<std::pair<std::size_t, double>>> jacobian(n);
    for (std::size_t k = 0; k < n; ++k) {
      double delta = kJacobianStepPx;
      std::vector<double> moved = theta;
      moved[k] += delta;
      auto shifted = taps_of(motion_of(moved));
      if (shifted.empty()) {  // a slot would go backwards: difference the other way
        delta = -delta;
        moved[k] = theta[k] + delta;
        shifted = taps_of(motion_of(moved));
        if (shifted.empty()) continue;
      }
      for (std::size_t c = 0; c < h.size(); ++c)
        for (std::size_t i = 0; i < p; ++i)
          if (const double d = shifted[c][i] - h[c][i]; d != 0)
            jacobian[k].emplace_back(c * p + i, d / delta);
    }
    // A h, and A J column by column as the sum of A's rows (A is symmetric)
    // weighted by the column's non-zero entries: contiguous, so it vectorises.
    std::vector<double> aj(rows * n, 0.0), ah(rows, 0.0);
    for (std::size_t r = 0; r < rows; ++r) {
      const double* row = a.data() + r * rows;
      double sum = 0;
#pragma omp simd reduction(+ : sum)
      for (std::size_t i = 0; i < rows; ++i) sum += row[i] * stacked[i];
      ah[r] = sum;
    }
    for (std::size_t k = 0; k < n; ++k) {
      double* column = aj.data() + k * rows;
      for (const auto& entry : jacobian[k]) {
        // Named copies: clang 14 refuses a structured binding inside an OpenMP simd loop.
        const double* row = a.data() + entry.first * rows;
        const double v = entry.second;
#pragma omp simd
        for (std::size_t r = 0; r < rows; ++r) column[r] += v * row[r];
      }
    }
    std::vector<double> normal(n * n, 0.0), gradient(n, 0.0);
    for (std::size_t k = 0; k < n; ++k) {
      for (const auto& [i, v] : jacobian[k]) gradient[k] += v * ah[i];
      for (std::size_t l = 0; l <= k; ++l) {
        double sum = 0;
        for (const auto& [i, v] : jacobian[k]) sum += v * aj[l * rows + i];
        normal[k * n + l] = normal[l * n + k] = sum;
      }
    }
    // The prior 0.5 w sum (o_k - o_{k-1})^2 over the offsets (indices 1..n-1, 0 at both ends).
    for (std::size_t k = 1; k < n; ++k) {
      const double before = k > 1 ? theta[k - 1] : 0, after = k + 1 < n ? theta[k + 1] : 0;
      gradient[k] += prior_weight * (2 * theta[k] - before - after);
      normal[k * n + k] += 2 * prior_weight;
      if (k > 1) normal[k * n + k - 1] -= prior_weight, normal[(k - 1) * n + k] -= prior_weight;
    }
    return {std::move(normal), std::move(gradient)};
  }

  /// Sandwich standard error of the blur over the blocks of rows (infinite where
  /// the residual does not curve up around `motion`).
  double standard_error(const Motion& motion) const {
    const double slot = model_.blur_px / model_.code.length();
    const double h = std::max(0.02, 0.1 * slot);
    const double below = std::max(lo_, motion.blur - h), above = std::min(hi_, motion.blur + h);
    const auto taps_below = taps_of({below, motion.ratio, motion.offsets});
    const auto taps_above = taps_of({above, motion.ratio, motion.offsets});
    const auto taps = taps_of(motion);
    if (taps_below.empty() || taps_above.empty() || taps.empty())  // a slot would go backwards
      return std::numeric_limits<double>::infinity();
    // The blocks' residuals sum to the whole: the curvature needs the whole only.
    const auto whole = forms_(taps, variances_, -1);
    double gradient_variance = 0, sum_below = 0, sum_above = 0;
    for (int k = 0; k < kBlocks; ++k) {
      const double fb = forms_(taps_below, variances_, k).value,
                   fa = forms_(taps_above, variances_, k).value;
      gradient_variance += square((fa - fb) / (above - below));
      sum_below += fb;
      sum_above += fa;
    }
    const double half = (above - below) / 2;
    const double curvature = (sum_above - 2 * whole.value + sum_below) / (half * half);
    return curvature > 0 ? std::sqrt(gradient_variance) / curvature
                         : std::numeric_limits<double>::infinity();
  }

  /// Whether the encoder's blur is off by more than the tolerance (the refined
  /// blur outside range_, beyond 3 standard errors) or the search's best blur
  /// lies on its edge (the best may lie beyond it).
  void mark_outside_tolerance(MotionRefinement& out) const {
    const double slot = model_.blur_px / model_.code.length();
    const double edge_margin = std::max(0.02, slot / 4);
    const double grace = 3 * out.standard_error_px;
    out.outside_tolerance = out.blur_px < range_.lo - grace || out.blur_px > range_.hi + grace ||
                            out.blur_px - lo_ < edge_margin || hi_ - out.blur_px < edge_margin;
  }

  /// Each channel's PSF taps for `motion`; empty when its offsets would move
  /// the object backwards.
  std::vector<std::vector<double>> taps_of(const Motion& motion) const {
    // (slot_edges() of the model with this motion, without copying the model.)
    auto edges = accelerating_slot_edges(model_.code.length(), std::clamp(motion.blur, lo_, hi_),
                                         motion.ratio);
    add_block_offsets(edges, motion.offsets);
    if (!edges_move_forward(edges)) return {};
    auto out = timeline_channel_psfs(model_, segments_from_boundaries(model_.code, edges));
    for (auto& t : out) t.resize(static_cast<std::size_t>(taps_), 0.0);
    return out;
  }

  /// The residual per sample of `motion` over every row (infinite for a motion
  /// that moves backwards).
  double mean(const Motion& motion) const {
    const auto taps = taps_of(motion);
    if (taps.empty()) return std::numeric_limits<double>::infinity();
    return forms_(taps, variances_, -1).mean();
  }

  const ResidualForms& forms_;
  const std::vector<double>& variances_;
  const CaptureModel& model_;
  BlurRange range_;
  double lo_, hi_;  ///< the blurs searched
  int taps_;
};

}  // namespace

bool refinement_fits(const CaptureModel& model, double tolerance, int along) {
  if (!(tolerance >= 0 && tolerance < kMaxBlurTolerance)) return false;
  const double hi = blur_range(model, tolerance).search_hi;
  if (!(hi >= 0 && hi < along)) return false;  // also: not a number
  // Differenced rows are one shorter than the frame.
  return 2 * static_cast<double>(pixel_model_taps(hi, model.pixel_model)) + 1 <= along;
}

Result<MotionRefinement, std::string> refine_motion(const MotionFrame& frame,
                                                    const CaptureModel& model,
                                                    const MotionRefinementOptions& options) {
  using Out = Result<MotionRefinement, std::string>;
  if (!std::isfinite(options.tolerance) || options.tolerance < 0 ||
      options.tolerance >= kMaxBlurTolerance)
    return Out::failure("the blur tolerance must be a finite fraction >= 0 and < 1 (100%)");
  if (options.rows < kBlocks)
    return Out::failure("refining the motion needs at least " + std::to_string(kBlocks) + " rows");
  if (frame.channel_count() < 2 || frame.channel_count() != model.channels)
    return Out::failure("refining the motion needs two or more channels lit by different codes");
  if (auto problem = capture_model_problem(model); !problem.empty()) return Out::failure(problem);
  if (!(model.blur_px > 0)) return Out::failure("refining the motion needs a blur > 0");
  if (channels_share_one_code(model))
    return Out::failure(
        "every channel sees the same code, so the frame carries no motion information this way: "
        "refining the motion needs a multi-LED code such as a one-of-3 triplet");
  const BlurRange range = blur_range(model, options.tolerance);
  const double hi = range.search_hi;
  if (!refinement_fits(model, options.tolerance, frame.along()))
    return Out::failure("the largest blur searched (" + std::to_string(hi) +
                        " px) does not fit the frame along the motion (" +
                        std::to_string(frame.along()) + " px)");
  const int taps = static_cast<int>(pixel_model_taps(hi, model.pixel_model));
  if (frame.lines() < kBlocks)
    return Out::failure("the frame has too few rows along the motion to refine the blur");

  // The edgiest rows of the brightest channel, read in batches (best first).
  std::size_t brightest = 0;
  {
    double best = -1;
    for (int c = 0; c < model.channels; ++c) {
      const double level = channel_white_electrons(model, c);
      if (level > best) best = level, brightest = static_cast<std::size_t>(c);
    }
  }
  const auto chosen = edgiest_rows(frame.channel(static_cast<int>(brightest)), options.rows);
  if (static_cast<int>(chosen.size()) < kBlocks)
    return Out::failure("the frame has too few rows along the motion to refine the blur");
  // Without a search there is nothing to stop early for: every row at once.
  std::size_t batch = options.tolerance > 0
                          ? std::min(chosen.size(), static_cast<std::size_t>(kFirstRows))
                          : chosen.size();
  const auto [from, to] = edge_stretch(
      frame.channel(static_cast<int>(brightest)),
      std::vector<int>(chosen.begin(), chosen.begin() + static_cast<std::ptrdiff_t>(batch)), taps);
  const std::size_t width = to - from + 1;

  ResidualForms forms(taps, frame.channel_count(), static_cast<int>(width));
  std::vector<RowSet> rows;
  std::vector<double> sums(static_cast<std::size_t>(frame.channel_count()), 0.0);
  std::vector<double> variances(sums.size());
  MotionRefinement out;
  double last_significance = 0;
  for (;;) {
    const std::size_t first = rows.size();
    for (std::size_t i = first; i < batch; ++i) {
      RowSet per_channel;
      for (int c = 0; c < frame.channel_count(); ++c) {
        const auto line = frame.channel(c).row(chosen[i]);
        // The row's mean level sets its noise (whole row, as the belt around the labels).
        const float* samples = line.data();
        const std::size_t count = line.size() - 1;
        float sum = 0;  // in float (vectorised); the rows in double
#pragma omp simd reduction(+ : sum)
        for (std::size_t n = 0; n < count; ++n) sum += samples[n];
        sums[static_cast<std::size_t>(c)] += sum / static_cast<double>(count);
        std::vector<float> diff(width);
        for (std::size_t n = 0; n < width; ++n) diff[n] = line[from + n + 1] - line[from + n];
        per_channel.push_back(std::move(diff));
      }
      rows.push_back(std::move(per_channel));
    }
    forms.add(rows, first, rows.size());
    for (std::size_t c = 0; c < sums.size(); ++c)
      variances[c] =
          channel_noise_variance(model, std::max(0.0, sums[c] / static_cast<double>(rows.size())));
    const MotionSearch search(forms, variances, model, range, taps);
    out = search.run(options);
    const bool precise = out.edges && out.standard_error_px <= kEnoughPrecisionPx;
    const double reachable = out.significance * std::sqrt(static_cast<double>(chosen.size()) /
                                                          static_cast<double>(rows.size()));
    // Rows come edgiest first: once a batch lowered the significance, the rows
    // left would lower it further.
    const bool flat =
        !out.edges && (reachable < kMinimumSignificance || out.significance < last_significance);
    last_significance = out.significance;
    if (rows.size() == chosen.size() || precise || flat || options.tolerance == 0) {
      if (options.speed_change && options.tolerance > 0) search.wander(out);
      break;
    }
    // The rows that bring the error below kEnoughPrecisionPx (a fifth more, whole
    // blocks), at least twice as many when the frame gave no error yet.
    const double wanted = out.edges ? 1.2 * static_cast<double>(rows.size()) *
                                          square(out.standard_error_px / kEnoughPrecisionPx)
                                    : 2.0 * static_cast<double>(rows.size());
    const auto blocks = static_cast<std::size_t>(std::ceil(wanted / kBlocks));
    batch = std::min(chosen.size(), std::max(rows.size() + kBlocks, blocks * kBlocks));
  }
  return Out::success(out);
}

bool refinement_usable(const MotionRefinement& r) {
  return r.edges && !r.outside_tolerance && r.residual_per_sample <= kUnfitMotionResidual;
}

CaptureModel with_refined_motion(CaptureModel model, const MotionRefinement& refinement) {
  model.blur_px = refinement.blur_px;
  model.speed_ratio = refinement.speed_ratio;
  model.block_offsets_px = refinement.block_offsets_px;
  return model;
}

CaptureModel motion_refined(const MotionFrame& frame, const CaptureModel& model, double tolerance) {
  if (!(tolerance > 0) || channels_share_one_code(model) ||
      !refinement_fits(model, tolerance, frame.along()))
    return model;
  MotionRefinementOptions options;
  options.tolerance = tolerance;
  const auto r = refine_motion(frame, model, options);
  return r.ok() && refinement_usable(r.value()) ? with_refined_motion(model, r.value()) : model;
}

}  // namespace flutterscan::imaging
