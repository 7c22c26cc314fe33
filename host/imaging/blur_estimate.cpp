#include "imaging/blur_estimate.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <memory>
#include <numeric>
#include <vector>

#include "imaging/golden_section.hpp"
#include "imaging/image_checks.hpp"
#include "imaging/joint_wiener.hpp"
#include "imaging/motion_frame.hpp"
#include "imaging/row_fft.hpp"

namespace flutterscan::imaging {
namespace {

constexpr int kBlocks = 16;
/// Below this contrast the residual barely depends on the blur (noise moves it by
/// about 0.01 on a 640x360 frame; frames with label edges reach 10 and more).
constexpr double kMinimumContrast = 0.1;

/// The frame's rows (along the motion) as zero-padded spectra, and what the cost needs.
class ConsistencyCost {
 public:
  /// Every `row_step`-th row of the frame (along the motion) takes part.
  ConsistencyCost(const MotionFrame& frame, const CaptureModel& model, int longest_psf,
                  int row_step = 1)
      : model_(model) {
    width_ = frame.along();
    height_ = (frame.lines() + row_step - 1) / row_step;
    fft_ = std::make_unique<RowFft>(row_fft_length(width_ + longest_psf));
    bins_ = static_cast<std::size_t>(fft_->bins());
    const auto n = static_cast<std::size_t>(fft_->length());
    AlignedFloats padded(n);
    product_ = AlignedFloats(2 * bins_);
    residual_ = AlignedFloats(n);
    for (const Plane& plane : frame.image().channels) {
      double sum = 0;
      AlignedFloats spectra(2 * bins_ * static_cast<std::size_t>(height_));
      for (int y = 0; y < height_; ++y) {
        std::fill(padded.data(), padded.data() + n, 0.0f);
        const auto row = plane.row(y * row_step);
        std::copy(row.begin(), row.end(), padded.data());
        sum += std::accumulate(row.begin(), row.end(), 0.0);
        // FFTW plans want the alignment they were made with: transform into the
        // aligned scratch, then store.
        fft_->forward(padded.data(), product_.complex());
        std::copy(product_.complex(), product_.complex() + bins_,
                  spectra.complex() + static_cast<std::size_t>(y) * bins_);
      }
      const double mean = sum / (static_cast<double>(width_) * height_);
      variances_.push_back(channel_noise_variance(model, std::max(0.0, mean)));
      spectra_.push_back(std::move(spectra));
    }
  }

  int height() const { return height_; }
  int width() const { return width_; }

  struct Residual {
    double sum = 0;           ///< of e^2 / var(e)
    std::size_t samples = 0;  ///< valid samples summed
    double mean() const { return samples > 0 ? sum / static_cast<double>(samples) : 0; }
  };

  /// e^2 / var(e) over the valid samples of rows [from, to) for blur `blur_px`.
  Residual operator()(double blur_px, int from, int to) {
    CaptureModel m = model_;
    m.blur_px = blur_px;
    const auto channels = spectra_.size();
    std::vector<std::vector<double>> taps(channels);
    std::vector<AlignedFloats> psf(channels);
    std::size_t longest = 1;
    for (std::size_t c = 0; c < channels; ++c) {
      taps[c] = channel_psf(m, static_cast<int>(c));
      longest = std::max(longest, taps[c].size());
      const auto spectrum = psf_spectrum(taps[c], fft_->length());
      psf[c] = AlignedFloats(2 * bins_);
      for (std::size_t j = 0; j < bins_; ++j)
        psf[c].complex()[j] = std::complex<float>(spectrum[j]);
    }
    const auto first_valid = longest - 1;
    const auto last = static_cast<std::size_t>(width_);  // exclusive
    if (first_valid >= last) return {};
    const double n = fft_->length();
    double sum = 0;
    std::size_t samples = 0;
    for (std::size_t c = 0; c < channels; ++c)
      for (std::size_t d = c + 1; d < channels; ++d) {
        auto power = [](const std::vector<double>& t) {
          double p = 0;
          for (double v : t) p += v * v;
          return p;
        };
        const double variance = variances_[c] * power(taps[d]) + variances_[d] * power(taps[c]);
        if (!(variance > 0)) continue;
        const double scale = 1.0 / (n * n * variance);
        for (int y = from; y < to; ++y) {
          const auto at = static_cast<std::size_t>(y) * bins_;
          const std::complex<float>* yc = spectra_[c].complex() + at;
          const std::complex<float>* yd = spectra_[d].complex() + at;
          std::complex<float>* e = product_.complex();
          for (std::size_t j = 0; j < bins_; ++j)
            e[j] = psf[d].complex()[j] * yc[j] - psf[c].complex()[j] * yd[j];
          fft_->inverse(e, residual_.data());
          double row_sum = 0;
          for (std::size_t i = first_valid; i < last; ++i)
            row_sum += static_cast<double>(residual_[i]) * residual_[i];
          sum += row_sum * scale;
          samples += last - first_valid;
        }
      }
    return {sum, samples};
  }

 private:
  CaptureModel model_;
  int width_ = 0, height_ = 0;
  std::unique_ptr<RowFft> fft_;
  std::size_t bins_ = 0;
  std::vector<AlignedFloats> spectra_;
  std::vector<double> variances_;
  AlignedFloats product_, residual_;
};

}  // namespace

Result<BlurEstimate, std::string> estimate_blur(const MotionFrame& frame, const CaptureModel& model,
                                                double min_px, double max_px, int row_step) {
  using Out = Result<BlurEstimate, std::string>;
  if (!(min_px > 0) || !(max_px > min_px) || !std::isfinite(max_px))
    return Out::failure("the blur search range must satisfy 0 < min < max");
  if (frame.channel_count() < 2 || frame.channel_count() != model.channels)
    return Out::failure("estimating the blur needs two or more channels lit by different codes");
  CaptureModel nominal = model;
  nominal.blur_px = (min_px + max_px) / 2;
  if (auto problem = capture_model_problem(nominal); !problem.empty()) return Out::failure(problem);
  if (channels_share_one_code(nominal))
    return Out::failure(
        "every channel sees the same code, so the frame carries no blur information this way: "
        "estimating the blur needs a multi-LED code such as a one-of-3 triplet");
  if (row_step < 1) return Out::failure("the row step must be 1 or more");
  // Before anything is sized by the blur: the largest blur searched.
  if (auto problem = model_scale_problem(model); !problem.empty()) return Out::failure(problem);
  if (auto problem = blur_fit_problem(max_px, frame.along(), 2, "the largest blur searched");
      !problem.empty())
    return Out::failure(problem);
  ConsistencyCost cost(frame, model, static_cast<int>(std::floor(max_px)) + 2, row_step);
  if (max_px + 2 >= cost.width())
    return Out::failure("the largest blur searched (" + std::to_string(max_px) +
                        " px) does not fit the frame along the motion (" +
                        std::to_string(cost.width()) + " px)");
  const int height = cost.height();
  if (height < kBlocks) return Out::failure("the frame has too few rows to estimate the blur");

  // A coarse grid over the whole range, then golden section around the best grid point.
  const double step = std::max(0.25, (max_px - min_px) / 120.0);
  double best = min_px, best_cost = INFINITY;
  std::vector<double> grid;
  for (double b = min_px; b <= max_px + 1e-9; b += step) {
    const double c = cost(b, 0, height).mean();
    grid.push_back(c);
    if (c < best_cost) {
      best_cost = c;
      best = b;
    }
  }
  std::nth_element(grid.begin(), grid.begin() + static_cast<std::ptrdiff_t>(grid.size() / 2),
                   grid.end());
  BlurEstimate estimate;
  estimate.blur_px =
      golden_minimum([&](double b) { return cost(b, 0, height).mean(); },
                     std::max(min_px, best - step), std::min(max_px, best + step), 0.005);
  estimate.residual_per_sample = cost(estimate.blur_px, 0, height).mean();
  estimate.contrast = grid[grid.size() / 2] / estimate.residual_per_sample - 1;

  // Sandwich standard error over row blocks: var(b) = sum_k R_k'^2 / (sum_k R_k'')^2,
  // derivatives of each block's residual sum by central differences.
  const double h = 0.1;
  const double lo = std::max(min_px, estimate.blur_px - h),
               hi = std::min(max_px, estimate.blur_px + h);
  double gradient_variance = 0, curvature = 0;
  for (int k = 0; k < kBlocks; ++k) {
    const int from = height * k / kBlocks, to = height * (k + 1) / kBlocks;
    const double below = cost(lo, from, to).sum, at = cost(estimate.blur_px, from, to).sum,
                 above = cost(hi, from, to).sum;
    const double gradient = (above - below) / (hi - lo);
    gradient_variance += gradient * gradient;
    curvature += (above - 2 * at + below) / (((hi - lo) / 2) * ((hi - lo) / 2));
  }
  estimate.standard_error_px = curvature > 0 && estimate.contrast >= kMinimumContrast
                                   ? std::sqrt(gradient_variance) / curvature
                                   : std::numeric_limits<double>::infinity();
  return Out::success(estimate);
}

Result<double, std::string> cross_channel_residual(const MotionFrame& frame,
                                                   const CaptureModel& model, int row_step) {
  using Out = Result<double, std::string>;
  if (frame.channel_count() < 2 || frame.channel_count() != model.channels)
    return Out::failure("the cross-channel residual needs two or more channels");
  if (auto problem = capture_model_problem(model); !problem.empty()) return Out::failure(problem);
  if (row_step < 1) return Out::failure("the row step must be 1 or more");
  // Before anything is sized by the blur (the cost's rows are padded by it).
  if (auto problem = model_scale_problem(model); !problem.empty()) return Out::failure(problem);
  if (auto problem = blur_fit_problem(model.blur_px, frame.along(), 2, "the blur");
      !problem.empty())
    return Out::failure(problem);
  ConsistencyCost cost(frame, model, static_cast<int>(std::floor(model.blur_px)) + 2, row_step);
  if (model.blur_px + 2 >= cost.width())
    return Out::failure("the blur does not fit the frame along the motion");
  return Out::success(cost(model.blur_px, 0, cost.height()).mean());
}

}  // namespace flutterscan::imaging
