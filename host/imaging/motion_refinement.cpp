#include "imaging/motion_refinement.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <numeric>
#include <vector>

#include "imaging/golden_section.hpp"
#include "imaging/motion_frame.hpp"
#include "imaging/row_fft.hpp"

namespace flutterscan::imaging {
namespace {

constexpr int kBlocks = 8;
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

double square(double v) {
  return v * v;
}

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

/// Cuts every row to the stretch along the motion where the rows of channel
/// `channel` have edges (columns whose summed |difference| is well above the
/// median column's, i.e. the labels), widened by `taps` samples on either side
/// and to at least 4 `taps`: the rest is belt, whose samples add noise but no
/// information, and shorter rows make every FFT cheaper.
void crop_to_edges(std::vector<std::vector<std::vector<float>>>& rows, std::size_t channel,
                   int taps) {
  const std::size_t width = rows[0][0].size();
  std::vector<float> energy(width, 0.0f);
  for (const auto& row : rows) {
    const float* d = row[channel].data();
#pragma omp simd
    for (std::size_t n = 0; n < width; ++n) energy[n] += std::abs(d[n]);
  }
  std::vector<float> sorted = energy;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(width / 2),
                   sorted.end());
  const float floor = 3 * sorted[width / 2];
  std::size_t lo = width, hi = 0;
  for (std::size_t n = 0; n < width; ++n)
    if (energy[n] > floor) lo = std::min(lo, n), hi = n;
  if (lo > hi) return;  // nothing stands out: keep the whole rows
  const auto margin = static_cast<std::size_t>(taps);
  lo = lo > margin ? lo - margin : 0;
  hi = std::min(width - 1, hi + margin);
  const std::size_t least = 4 * margin;
  while (hi - lo + 1 < least && (lo > 0 || hi + 1 < width)) {
    if (lo > 0) --lo;
    if (hi + 1 < width) ++hi;
  }
  if (lo == 0 && hi + 1 == width) return;
  for (auto& row : rows)
    for (auto& channel_row : row)
      channel_row = std::vector<float>(channel_row.begin() + static_cast<std::ptrdiff_t>(lo),
                                       channel_row.begin() + static_cast<std::ptrdiff_t>(hi + 1));
}

/// The residual of every candidate motion as quadratic forms in its taps
/// (motion_refinement.hpp): G_ab per block of rows and pair of channels.
class ResidualForms {
 public:
  /// rows[r][c]: differenced row r of channel c (all of one length); block of row r = r % kBlocks.
  ResidualForms(const std::vector<std::vector<std::vector<float>>>& rows, int taps)
      : taps_(taps), channels_(static_cast<int>(rows[0].size())) {
    const int width = static_cast<int>(rows[0][0].size());
    valid_ = width - (taps - 1);
    const RowFft fft(row_fft_length(width + taps));
    const auto n = static_cast<std::size_t>(fft.length());
    const auto bins = static_cast<std::size_t>(fft.bins());
    const auto p = static_cast<std::size_t>(taps);
    const auto pairs = static_cast<std::size_t>(channels_ * (channels_ + 1) / 2);
    gram_.assign(kBlocks * pairs, std::vector<double>(p * p, 0.0));
    rows_in_block_.assign(kBlocks, 0);

    AlignedFloats padded(n), correlation(n);
    // One aligned buffer per spectrum: FFTW's plans want the alignment they were made with.
    std::vector<AlignedFloats> spectra, cross;
    std::vector<double> head_b(p), tail_b(p);
    for (int c = 0; c < channels_; ++c) spectra.emplace_back(2 * bins);
    for (std::size_t q = 0; q < pairs; ++q) cross.emplace_back(2 * bins);
    // Per block: the cross-spectra summed over its rows, and the exact corrections.
    for (int block = 0; block < kBlocks; ++block) {
      for (auto& s : cross) std::fill(s.data(), s.data() + 2 * bins, 0.0f);
      std::vector<std::vector<double>> base_ab(pairs, std::vector<double>(p, 0.0)),
          base_ba(pairs, std::vector<double>(p, 0.0));
      std::vector<std::vector<double>> ends(pairs, std::vector<double>(p * p, 0.0));
      for (std::size_t r = static_cast<std::size_t>(block); r < rows.size(); r += kBlocks) {
        ++rows_in_block_[static_cast<std::size_t>(block)];
        for (int c = 0; c < channels_; ++c) {
          const auto& row = rows[r][static_cast<std::size_t>(c)];
          std::fill(padded.data(), padded.data() + n, 0.0f);
          std::copy(row.begin(), row.end(), padded.data());
          fft.forward(padded.data(), spectra[static_cast<std::size_t>(c)].complex());
        }
        std::size_t q = 0;
        for (int a = 0; a < channels_; ++a)
          for (int b = a; b < channels_; ++b, ++q) {
            // sum_n a[n] b[n - k] has the spectrum A conj(B).
            accumulate_spectra(spectra[static_cast<std::size_t>(b)].data(),
                               spectra[static_cast<std::size_t>(a)].data(), cross[q].data(), bins,
                               true);
            const auto& ra = rows[r][static_cast<std::size_t>(a)];
            const auto& rb = rows[r][static_cast<std::size_t>(b)];
            const std::size_t first = p - 1;  // F, the first valid sample
            // G[0][j] lacks sum_{n=j}^{F-1} a[n] b[n-j]; G[i][0] lacks the mirror.
            for (std::size_t j = 0; j < first; ++j) {
              double head_ab = 0, head_ba = 0;
              const float* a_from = ra.data() + j;
              const float* b_from = rb.data() + j;
              const std::size_t count = first - j;
#pragma omp simd reduction(+ : head_ab, head_ba)
              for (std::size_t k = 0; k < count; ++k) {
                head_ab += static_cast<double>(a_from[k]) * rb[k];
                head_ba += static_cast<double>(b_from[k]) * ra[k];
              }
              base_ab[q][j] -= head_ab;
              base_ba[q][j] -= head_ba;
            }
            // G[i+1][j+1] = G[i][j] + a[F-1-i] b[F-1-j] - a[W-1-i] b[W-1-j]: the
            // ends of b reversed into contiguous scratch, so the update vectorises.
            const std::size_t last = ra.size() - 1;
            for (std::size_t j = 0; j + 1 < p; ++j) {
              head_b[j] = rb[first - 1 - j];
              tail_b[j] = rb[last - j];
            }
            auto& e = ends[q];
            const std::size_t inner = p - 1;
            for (std::size_t i = 0; i < inner; ++i) {
              const double head_a = ra[first - 1 - i], tail_a = ra[last - i];
              double* out = e.data() + i * p;
              const double* hb = head_b.data();
              const double* tb = tail_b.data();
#pragma omp simd
              for (std::size_t j = 0; j < inner; ++j) out[j] += head_a * hb[j] - tail_a * tb[j];
            }
          }
      }
      for (std::size_t q = 0; q < pairs; ++q) {
        fft.inverse(cross[q].complex(), correlation.data());
        const double scale = 1.0 / static_cast<double>(n);
        auto& g = gram_[static_cast<std::size_t>(block) * pairs + q];
        for (std::size_t j = 0; j < p; ++j) {
          g[j] = correlation[j] * scale + base_ab[q][j];                // G[0][j]
          g[j * p] = correlation[(n - j) % n] * scale + base_ba[q][j];  // G[j][0]
        }
        for (std::size_t i = 1; i < p; ++i)
          for (std::size_t j = 1; j < p; ++j)
            g[i * p + j] = g[(i - 1) * p + j - 1] + ends[q][(i - 1) * p + j - 1];
      }
    }
    // The sums over every block, for the search (blocks only for the standard error).
    for (std::size_t q = 0; q < pairs; ++q) {
      std::vector<double> total(p * p, 0.0);
      for (int block = 0; block < kBlocks; ++block) {
        const auto& g = gram_[static_cast<std::size_t>(block) * pairs + q];
        for (std::size_t i = 0; i < total.size(); ++i) total[i] += g[i];
      }
      gram_.push_back(std::move(total));
    }
    rows_in_block_.push_back(static_cast<int>(rows.size()));
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
    const auto pairs = static_cast<std::size_t>(channels_ * (channels_ + 1) / 2);
    // |difference of h|^2: the noise of a differenced residual.
    std::vector<double> power(taps.size());
    for (std::size_t c = 0; c < taps.size(); ++c) {
      double sum = 0, previous = 0;
      for (double t : taps[c]) {
        sum += square(t - previous);
        previous = t;
      }
      power[c] = sum + square(previous);
    }
    Sum total;
    const int k = block < 0 ? kBlocks : block;  // the totals follow the blocks
    {
      const auto rows = static_cast<std::size_t>(rows_in_block_[static_cast<std::size_t>(k)]);
      for (int c = 0; c < channels_; ++c)
        for (int d = c + 1; d < channels_; ++d) {
          const auto uc = static_cast<std::size_t>(c), ud = static_cast<std::size_t>(d);
          const double variance = variances[uc] * power[ud] + variances[ud] * power[uc];
          if (!(variance > 0)) continue;
          const auto& g_cc = gram_[static_cast<std::size_t>(k) * pairs + pair_index(c, c)];
          const auto& g_dd = gram_[static_cast<std::size_t>(k) * pairs + pair_index(d, d)];
          const auto& g_cd = gram_[static_cast<std::size_t>(k) * pairs + pair_index(c, d)];
          const double energy = form(taps[ud], g_cc, taps[ud], p) +
                                form(taps[uc], g_dd, taps[uc], p) -
                                2 * form(taps[ud], g_cd, taps[uc], p);
          total.value += energy / variance;
          total.samples += rows * static_cast<std::size_t>(valid_);
        }
    }
    return total;
  }

 private:
  std::size_t pair_index(int a, int b) const {
    // (a, b), a <= b, in the order the constructor fills them.
    std::size_t q = 0;
    for (int i = 0; i < channels_; ++i)
      for (int j = i; j < channels_; ++j, ++q)
        if (i == a && j == b) return q;
    return q;
  }

  static double form(const std::vector<double>& x, const std::vector<double>& g,
                     const std::vector<double>& y, std::size_t p) {
    double sum = 0;
    for (std::size_t i = 0; i < p; ++i) {
      if (x[i] == 0) continue;
      const double* row = g.data() + i * p;
      double inner = 0;
      for (std::size_t j = 0; j < p; ++j) inner += row[j] * y[j];
      sum += x[i] * inner;
    }
    return sum;
  }

  int taps_;
  int channels_;
  int valid_ = 0;
  /// [block * pairs + pair], P x P row-major; "block" kBlocks holds the sums over all.
  std::vector<std::vector<double>> gram_;
  std::vector<int> rows_in_block_;  ///< kBlocks + 1 entries, the last all rows
};

}  // namespace

bool refinement_fits(const CaptureModel& model, double tolerance, int along) {
  const double hi = model.blur_px * (1 + tolerance);
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
  const double lo = model.blur_px * (1 - options.tolerance);
  const double hi = model.blur_px * (1 + options.tolerance);
  if (!refinement_fits(model, options.tolerance, frame.along()))
    return Out::failure("the largest blur searched (" + std::to_string(hi) +
                        " px) does not fit the frame along the motion (" +
                        std::to_string(frame.along()) + " px)");
  const int taps = static_cast<int>(pixel_model_taps(hi, model.pixel_model));
  if (frame.lines() < kBlocks)
    return Out::failure("the frame has too few rows along the motion to refine the blur");

  // The edgiest rows of the brightest channel, differenced, every channel.
  std::size_t brightest = 0;
  {
    double best = -1;
    for (int c = 0; c < model.channels; ++c) {
      const double level = channel_white_electrons(model, c);
      if (level > best) best = level, brightest = static_cast<std::size_t>(c);
    }
  }
  const auto chosen = edgiest_rows(frame.channel(static_cast<int>(brightest)), options.rows);
  std::vector<std::vector<std::vector<float>>> rows;
  std::vector<double> means(static_cast<std::size_t>(frame.channel_count()), 0.0);
  for (int r : chosen) {
    std::vector<std::vector<float>> per_channel;
    for (int c = 0; c < frame.channel_count(); ++c) {
      const auto line = frame.channel(c).row(r);
      std::vector<float> diff(line.size() - 1);
      double sum = 0;
      for (std::size_t n = 0; n + 1 < line.size(); ++n) {
        diff[n] = line[n + 1] - line[n];
        sum += line[n];
      }
      means[static_cast<std::size_t>(c)] += sum / static_cast<double>(line.size() - 1);
      per_channel.push_back(std::move(diff));
    }
    rows.push_back(std::move(per_channel));
  }
  if (static_cast<int>(rows.size()) < kBlocks)
    return Out::failure("the frame has too few rows along the motion to refine the blur");
  crop_to_edges(rows, brightest, taps);
  std::vector<double> variances;
  for (double m : means)
    variances.push_back(channel_noise_variance(model, std::max(0.0, m / rows.size())));

  const ResidualForms forms(rows, taps);
  const auto taps_of = [&](double blur, double ratio) {
    CaptureModel m = model;
    m.blur_px = std::clamp(blur, lo, hi);
    m.speed_ratio = ratio;
    std::vector<std::vector<double>> out;
    for (int c = 0; c < model.channels; ++c) {
      auto t = channel_psf(m, c);
      t.resize(static_cast<std::size_t>(taps), 0.0);
      out.push_back(std::move(t));
    }
    return out;
  };
  const auto residual = [&](double blur, double ratio, int block = -1) {
    return forms(taps_of(blur, ratio), variances, block);
  };

  MotionRefinement out;
  out.rows_used = static_cast<int>(rows.size());
  out.blur_px = model.blur_px;
  out.speed_ratio = model.speed_ratio;
  const double slot = model.blur_px / model.code.length();
  const double start_ratio = model.speed_ratio;

  // Constant speed (the model's ratio): a grid of a quarter slot, then golden section.
  double best = model.blur_px;
  std::vector<double> grid;
  if (options.tolerance > 0) {
    const double step = std::max(0.02, slot / 4);
    double best_cost = INFINITY;
    for (double b = lo; b <= hi + 1e-9; b += step) {
      const double c = residual(b, start_ratio).mean();
      grid.push_back(c);
      if (c < best_cost) best_cost = c, best = b;
    }
    best = golden_minimum([&](double b) { return residual(b, start_ratio).mean(); },
                          std::max(lo, best - step), std::min(hi, best + step),
                          0.005 * std::max(1.0, slot));
  }
  out.constant_speed_residual = residual(best, start_ratio).mean();
  out.residual_per_sample = out.constant_speed_residual;
  if (grid.empty()) return Out::success(out);  // tolerance 0: the given motion, checked
  std::nth_element(grid.begin(), grid.begin() + static_cast<std::ptrdiff_t>(grid.size() / 2),
                   grid.end());
  out.contrast = grid[grid.size() / 2] / out.constant_speed_residual - 1;

  // The accelerating motion, when the constant one leaves a residual above the noise.
  double ratio = start_ratio;
  if (options.speed_change && out.contrast > 0 && out.constant_speed_residual > kAboveNoise) {
    double log_ratio = 0, best_cost = INFINITY;
    for (double x = -kLogRatioRange; x <= kLogRatioRange + 1e-9; x += 0.1) {
      const double c = residual(best, std::exp(x)).mean();
      if (c < best_cost) best_cost = c, log_ratio = x;
    }
    double blur = best;
    for (int pass = 0; pass < 2; ++pass) {
      const double r = std::exp(log_ratio);
      blur = golden_minimum([&](double b) { return residual(b, r).mean(); },
                            std::max(lo, blur - 2 * slot), std::min(hi, blur + 2 * slot),
                            0.005 * std::max(1.0, slot));
      log_ratio = golden_minimum([&](double x) { return residual(blur, std::exp(x)).mean(); },
                                 std::max(-kLogRatioRange, log_ratio - 0.15),
                                 std::min(kLogRatioRange, log_ratio + 0.15), 0.002);
    }
    const double accelerating = residual(blur, std::exp(log_ratio)).mean();
    if (accelerating < out.constant_speed_residual * (1 - kAccelerationGain)) {
      out.accelerating = true;
      best = blur;
      ratio = std::exp(log_ratio);
      out.residual_per_sample = accelerating;
    }
  }

  // Sandwich standard error of the blur over the blocks of rows.
  const double h = std::max(0.02, 0.1 * slot);
  const double below = std::max(lo, best - h), above = std::min(hi, best + h);
  double gradient_variance = 0, curvature = 0;
  for (int k = 0; k < kBlocks; ++k) {
    const double fb = residual(below, ratio, k).value, fa = residual(above, ratio, k).value,
                 f0 = residual(best, ratio, k).value;
    const double half = (above - below) / 2;
    gradient_variance += square((fa - fb) / (above - below));
    curvature += (fa - 2 * f0 + fb) / (half * half);
  }
  // Edges: the best blur explains the frame better than a typical one by far
  // more than noise could (the residual's spread over the samples is about
  // sqrt(2 / samples) per sample), and the residual curves up around it.
  const double samples = static_cast<double>(residual(best, ratio).samples);
  out.significance = out.contrast * out.constant_speed_residual * std::sqrt(samples / 2);
  out.edges = out.significance >= kMinimumSignificance && curvature > 0;
  out.standard_error_px = out.edges ? std::sqrt(gradient_variance) / curvature
                                    : std::numeric_limits<double>::infinity();
  if (!out.edges) {
    out.accelerating = false;
    out.residual_per_sample = out.constant_speed_residual;
    return Out::success(out);
  }
  out.blur_px = best;
  out.speed_ratio = ratio;
  const double edge_margin = std::max(0.02, slot / 4);
  out.at_range_edge = best - lo < edge_margin || hi - best < edge_margin;
  return Out::success(out);
}

}  // namespace flutterscan::imaging
