#include "imaging/per_channel_wiener.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <numbers>
#include <span>

#include "imaging/exposure_timeline.hpp"
#include "imaging/joint_wiener.hpp"
#include "imaging/row_fft.hpp"

namespace flutterscan::imaging {
namespace {

using Complex = std::complex<double>;
using Matrix3 = std::array<std::array<Complex, 3>, 3>;

/// Solves N X = B for X (3x3, Gaussian elimination with partial pivoting).
/// N is Hermitian positive definite here (lambda P > 0 off the DC bin; at DC
/// the data term alone), so a tiny pivot only occurs for a singular problem,
/// where the bin is left at zero.
Matrix3 solve3(Matrix3 n, Matrix3 b) {
  for (int col = 0; col < 3; ++col) {
    int pivot = col;
    for (int r = col + 1; r < 3; ++r)
      if (std::abs(n[r][col]) > std::abs(n[pivot][col])) pivot = r;
    std::swap(n[col], n[pivot]);
    std::swap(b[col], b[pivot]);
    if (std::abs(n[col][col]) < 1e-300) return Matrix3{};
    for (int r = 0; r < 3; ++r) {
      if (r == col) continue;
      const Complex f = n[r][col] / n[col][col];
      for (int k = 0; k < 3; ++k) {
        n[r][k] -= f * n[col][k];
        b[r][k] -= f * b[col][k];
      }
    }
  }
  for (int r = 0; r < 3; ++r)
    for (int k = 0; k < 3; ++k) b[r][k] /= n[r][r];
  return b;
}

/// Symmetric 3x3 eigen-decomposition by Jacobi rotations: eigenvectors as
/// columns of `vectors`, sorted by decreasing eigenvalue.
void symmetric_eigen(std::array<std::array<double, 3>, 3> a, std::array<double, 3>& values,
                     std::array<std::array<double, 3>, 3>& vectors) {
  std::array<std::array<double, 3>, 3> v{};
  for (int i = 0; i < 3; ++i) v[i][i] = 1;
  for (int sweep = 0; sweep < 50; ++sweep) {
    const double off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
    if (off < 1e-30) break;
    for (int p = 0; p < 2; ++p)
      for (int q = p + 1; q < 3; ++q) {
        if (std::abs(a[p][q]) < 1e-300) continue;
        const double theta = (a[q][q] - a[p][p]) / (2 * a[p][q]);
        const double t =
            (theta >= 0 ? 1.0 : -1.0) / (std::abs(theta) + std::sqrt(theta * theta + 1));
        const double c = 1 / std::sqrt(t * t + 1), s = t * c;
        for (int k = 0; k < 3; ++k) {  // a <- a J
          const double akp = a[k][p], akq = a[k][q];
          a[k][p] = c * akp - s * akq;
          a[k][q] = s * akp + c * akq;
        }
        for (int k = 0; k < 3; ++k) {  // a <- J^T a
          const double apk = a[p][k], aqk = a[q][k];
          a[p][k] = c * apk - s * aqk;
          a[q][k] = s * apk + c * aqk;
        }
        for (int k = 0; k < 3; ++k) {
          const double vkp = v[k][p], vkq = v[k][q];
          v[k][p] = c * vkp - s * vkq;
          v[k][q] = s * vkp + c * vkq;
        }
      }
  }
  std::array<int, 3> order{0, 1, 2};
  std::sort(order.begin(), order.end(), [&](int x, int y) { return a[x][x] > a[y][y]; });
  for (int i = 0; i < 3; ++i) {
    values[i] = a[order[i]][order[i]];
    for (int k = 0; k < 3; ++k) vectors[k][i] = v[k][order[i]];
  }
}

/// The bands r_k = offset_k + sum_i basis[i][k] a_i: K = basis.size() latents.
struct BandBasis {
  std::vector<std::array<double, 3>> basis;
  std::array<double, 3> offset{};
};

/// Solves for the K latents of `basis` per frequency from the three channels
/// (motion-frame rows); returns them as planes (motion frame). With `mix` (K weights), one
/// plane instead: sum_i mix[i] a_i, filtered as one (the sum is linear in each
/// bin). Each output is a filter of joint Wiener's shape (a transfer function
/// per channel, summed), so it runs on JointWiener's rows in pairs.
std::vector<Plane> solve_latents(const std::vector<Plane>& rows, const CaptureModel& model,
                                 std::span<const double> noise_variance, const BandBasis& bands,
                                 double lambda, const PerChannelOptions& options,
                                 std::span<const double> mix = {}) {
  const int width = rows[0].width;
  const int latents = static_cast<int>(bands.basis.size());
  const auto segments = slot_segments(model);
  CaptureModel ambient_only = model;
  std::fill(ambient_only.led_electrons.begin(), ambient_only.led_electrons.end(), 0.0);
  std::vector<std::vector<double>> led_taps, ambient_taps;
  std::size_t longest = 1;
  for (int k = 0; k < 3; ++k) {
    led_taps.push_back(timeline_led_psf(model, k, segments));
    ambient_taps.push_back(timeline_channel_psf(ambient_only, k, segments));
    longest = std::max({longest, led_taps.back().size(), ambient_taps.back().size()});
  }
  // The offset's share of each channel (a constant: the belt continues upstream).
  std::array<double, 3> offset_electrons{};
  for (int c = 0; c < 3; ++c)
    for (int k = 0; k < 3; ++k) {
      double white = 0;
      for (double t : led_taps[static_cast<std::size_t>(k)]) white += t;
      white *= model.crosstalk[static_cast<std::size_t>(c * 3 + k)];
      if (c == k)
        for (double t : ambient_taps[static_cast<std::size_t>(k)]) white += t;
      offset_electrons[static_cast<std::size_t>(c)] +=
          white * bands.offset[static_cast<std::size_t>(k)];
    }
  const int n = row_fft_length(width + static_cast<int>(longest));
  const auto bins = static_cast<std::size_t>(n / 2 + 1);
  std::vector<std::vector<Complex>> h, ambient;
  for (int k = 0; k < 3; ++k) {
    h.push_back(psf_spectrum(led_taps[static_cast<std::size_t>(k)], n));
    ambient.push_back(psf_spectrum(ambient_taps[static_cast<std::size_t>(k)], n));
  }
  // transfer[i][c][j]: latent i's weight on channel c's spectrum in bin j.
  std::vector<std::vector<std::vector<Complex>>> transfer(
      static_cast<std::size_t>(latents),
      std::vector<std::vector<Complex>>(3, std::vector<Complex>(bins)));
  for (std::size_t j = 0; j < bins; ++j) {
    Matrix3 a{};  // channel c from latent i: sum_k (M[c][k] H_k + ambient) basis[i][k]
    for (int c = 0; c < 3; ++c)
      for (int i = 0; i < latents; ++i)
        for (int k = 0; k < 3; ++k) {
          Complex g = model.crosstalk[static_cast<std::size_t>(c * 3 + k)] * h[k][j];
          if (c == k) g += ambient[c][j];
          a[c][i] += g * bands.basis[static_cast<std::size_t>(i)][static_cast<std::size_t>(k)];
        }
    Matrix3 normal{}, rhs{};  // A^H V^-1 A + lambda P I, and A^H V^-1 (identity past K)
    const double w = 2.0 * std::numbers::pi * static_cast<double>(j) / n;
    for (int i = 0; i < 3; ++i) {
      if (i >= latents) {
        normal[i][i] = 1;
        continue;
      }
      for (int l = 0; l < latents; ++l)
        for (int c = 0; c < 3; ++c)
          normal[i][l] +=
              std::conj(a[c][i]) * a[c][l] / noise_variance[static_cast<std::size_t>(c)];
      normal[i][i] += lambda * (2.0 - 2.0 * std::cos(w));
      for (int c = 0; c < 3; ++c)
        rhs[i][c] = std::conj(a[c][i]) / noise_variance[static_cast<std::size_t>(c)];
    }
    const Matrix3 x = solve3(normal, rhs);
    for (int i = 0; i < latents; ++i)
      for (int c = 0; c < 3; ++c)
        transfer[static_cast<std::size_t>(i)][static_cast<std::size_t>(c)][j] = x[i][c];
  }
  if (!mix.empty()) {
    std::vector<std::vector<Complex>> mixed(3, std::vector<Complex>(bins));
    for (std::size_t i = 0; i < transfer.size(); ++i)
      for (std::size_t c = 0; c < 3; ++c)
        for (std::size_t j = 0; j < bins; ++j) mixed[c][j] += mix[i] * transfer[i][c][j];
    transfer = {std::move(mixed)};
  }

  std::vector<Plane> out;
  for (const auto& output : transfer) {
    JointWiener filter(output, n, width, options.plan_effort);
    Plane latent = filter.deconvolve(rows, options.threads);
    // The offset, by linearity: the filter of y_c - o_c is the filter of y_c less
    // sum_c T_c(0) o_c (a constant row has only a DC bin).
    double shift = 0;
    for (std::size_t c = 0; c < 3; ++c) shift += output[c][0].real() * offset_electrons[c];
    if (shift != 0)
      for (float& p : latent.pixels) p -= static_cast<float>(shift);
    undo_psf_lead(latent, pixel_model_lead(model.pixel_model));
    out.push_back(std::move(latent));
  }
  return out;
}

/// Bands from latents: r_k = offset_k + sum_i basis[i][k] a_i.
std::vector<Plane> to_bands(const std::vector<Plane>& latents, const BandBasis& bands) {
  std::vector<Plane> out;
  for (int k = 0; k < 3; ++k) {
    Plane band(latents[0].width, latents[0].height,
               static_cast<float>(bands.offset[static_cast<std::size_t>(k)]));
    for (std::size_t i = 0; i < latents.size(); ++i) {
      const auto weight = static_cast<float>(bands.basis[i][static_cast<std::size_t>(k)]);
      for (std::size_t p = 0; p < band.pixels.size(); ++p)
        band.pixels[p] += weight * latents[i].pixels[p];
    }
    out.push_back(std::move(band));
  }
  return out;
}

/// The print plane of the bands (motion frame): their mean colour and the two
/// principal colour directions, over the columns past the first blur length.
BandBasis print_plane(const std::vector<Plane>& bands, double blur_px) {
  const int x0 = std::min(bands[0].width - 1, static_cast<int>(std::ceil(blur_px)));
  std::array<double, 3> mean{};
  std::array<std::array<double, 3>, 3> covariance{};
  double count = 0;
  for (int y = 0; y < bands[0].height; ++y)
    for (int x = x0; x < bands[0].width; ++x) {
      std::array<double, 3> v{};
      for (int k = 0; k < 3; ++k)
        v[static_cast<std::size_t>(k)] =
            std::clamp(bands[static_cast<std::size_t>(k)].at(x, y), 0.0f, 1.0f);
      for (int k = 0; k < 3; ++k) {
        mean[static_cast<std::size_t>(k)] += v[static_cast<std::size_t>(k)];
        for (int l = 0; l < 3; ++l)
          covariance[static_cast<std::size_t>(k)][static_cast<std::size_t>(l)] +=
              v[static_cast<std::size_t>(k)] * v[static_cast<std::size_t>(l)];
      }
      ++count;
    }
  for (auto& m : mean) m /= count;
  for (int k = 0; k < 3; ++k)
    for (int l = 0; l < 3; ++l)
      covariance[static_cast<std::size_t>(k)][static_cast<std::size_t>(l)] =
          covariance[static_cast<std::size_t>(k)][static_cast<std::size_t>(l)] / count -
          mean[static_cast<std::size_t>(k)] * mean[static_cast<std::size_t>(l)];
  std::array<double, 3> values{};
  std::array<std::array<double, 3>, 3> vectors{};
  symmetric_eigen(covariance, values, vectors);
  BandBasis plane;
  plane.offset = mean;
  for (int i = 0; i < 2; ++i)
    plane.basis.push_back({vectors[0][static_cast<std::size_t>(i)],
                           vectors[1][static_cast<std::size_t>(i)],
                           vectors[2][static_cast<std::size_t>(i)]});
  return plane;
}

}  // namespace

Result<PerChannelResult, std::string> deblur_per_channel(const MotionFrame& frame,
                                                         const CaptureModel& model, double lambda,
                                                         const PerChannelOptions& options) {
  using Out = Result<PerChannelResult, std::string>;
  if (auto problem = capture_model_problem(model); !problem.empty()) return Out::failure(problem);
  if (model.channels != 3 || model.leds != 3)
    return Out::failure("the per-channel model needs 3 channels and 3 LEDs");
  if (frame.channel_count() != 3)
    return Out::failure("the frame has " + std::to_string(frame.channel_count()) +
                        " channels; the per-channel model needs 3");
  if (!(lambda > 0) || !std::isfinite(lambda))
    return Out::failure("the prior weight lambda must be a finite number > 0");
  const std::vector<Plane>& rows = frame.image().channels;
  if (model.blur_px >= frame.along())
    return Out::failure("the blur (" + std::to_string(model.blur_px) +
                        " px) is not shorter than the image along the motion (" +
                        std::to_string(frame.along()) + " px)");
  PerChannelResult result;
  for (const auto& r : rows)
    result.noise_variance.push_back(channel_noise_variance(model, noise_level_mean(r)));
  BandBasis basis;
  basis.basis = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  if (options.prior == ColourPrior::kPrintPlane)
    basis = print_plane(solve_latents(rows, model, result.noise_variance, basis, lambda, options),
                        model.blur_px);
  if (options.output == PerChannelOutput::kGreyOnly) {
    // grey = mean_k r_k = mean_k offset_k + sum_i (mean_k basis[i][k]) a_i.
    std::vector<double> mix;
    for (const auto& b : basis.basis) mix.push_back((b[0] + b[1] + b[2]) / 3);
    result.grey = std::move(
        solve_latents(rows, model, result.noise_variance, basis, lambda, options, mix).front());
    const auto offset =
        static_cast<float>((basis.offset[0] + basis.offset[1] + basis.offset[2]) / 3);
    for (float& p : result.grey.pixels) p += offset;
    return Out::success(std::move(result));
  }
  std::vector<Plane> bands =
      solve_latents(rows, model, result.noise_variance, basis, lambda, options);
  if (options.prior == ColourPrior::kPrintPlane) bands = to_bands(bands, basis);
  result.grey = Plane(rows[0].width, rows[0].height);
  for (const auto& band : bands)
    for (std::size_t i = 0; i < band.pixels.size(); ++i)
      result.grey.pixels[i] += band.pixels[i] / 3.0f;
  result.bands = std::move(bands);
  return Out::success(std::move(result));
}

}  // namespace flutterscan::imaging
