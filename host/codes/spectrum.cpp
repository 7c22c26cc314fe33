#include "codes/spectrum.hpp"

#include <fftw3.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <mutex>
#include <numbers>

namespace flutterscan::codes {
namespace {

/// An FFTW real-to-complex plan of one size, made once and shared: planning is
/// not thread-safe in FFTW, executing with fftw_execute_dft_r2c is.
class RealDftPlan {
 public:
  explicit RealDftPlan(int size) : size_(size) {
    double* in = fftw_alloc_real(static_cast<std::size_t>(size));
    fftw_complex* out = fftw_alloc_complex(static_cast<std::size_t>(size / 2 + 1));
    plan_ = fftw_plan_dft_r2c_1d(size, in, out, FFTW_ESTIMATE);
    fftw_free(in);
    fftw_free(out);
  }
  ~RealDftPlan() { fftw_destroy_plan(plan_); }
  RealDftPlan(const RealDftPlan&) = delete;
  RealDftPlan& operator=(const RealDftPlan&) = delete;

  std::vector<std::complex<double>> run(std::span<const double> sequence) const {
    double* in = fftw_alloc_real(static_cast<std::size_t>(size_));
    fftw_complex* out = fftw_alloc_complex(static_cast<std::size_t>(size_ / 2 + 1));
    std::fill(in, in + size_, 0.0);
    std::copy(sequence.begin(), sequence.end(), in);
    fftw_execute_dft_r2c(plan_, in, out);
    std::vector<std::complex<double>> spectrum(static_cast<std::size_t>(size_ / 2 + 1));
    for (std::size_t j = 0; j < spectrum.size(); ++j) spectrum[j] = {out[j][0], out[j][1]};
    fftw_free(in);
    fftw_free(out);
    return spectrum;
  }

 private:
  int size_;
  fftw_plan plan_;
};

const RealDftPlan& plan_for(int size) {
  static std::mutex mutex;
  static std::map<int, std::unique_ptr<RealDftPlan>> plans;
  const std::lock_guard lock(mutex);
  auto& plan = plans[size];
  if (!plan) plan = std::make_unique<RealDftPlan>(size);
  return *plan;
}

SampledSpectrum to_db(const std::vector<std::complex<double>>& bins, int padded_size, int length) {
  SampledSpectrum out;
  out.frequency.resize(bins.size());
  out.db.resize(bins.size());
  for (std::size_t j = 0; j < bins.size(); ++j) {
    out.frequency[j] = static_cast<double>(j) / padded_size;
    out.db[j] = seed_db(std::abs(bins[j]), length);
  }
  return out;
}

}  // namespace

std::vector<double> led_sequence(const LedCode& code, int led) {
  std::vector<double> sequence(static_cast<std::size_t>(code.length()));
  for (int slot = 0; slot < code.length(); ++slot)
    sequence[static_cast<std::size_t>(slot)] = code.is_on(slot, led) ? 1.0 : 0.0;
  return sequence;
}

int seed_grid_size(int length) {
  int size = 1;
  while (size <= length) size *= 2;
  return size;
}

double seed_db(double magnitude, int length) {
  if (magnitude < kNullMagnitude) return kNullDb;
  return std::max(kNullDb, 20.0 * std::log10(magnitude / (seed_grid_size(length) / 2)));
}

std::complex<double> dtft(std::span<const double> sequence, double f) {
  std::complex<double> sum = 0;
  const double w = -2.0 * std::numbers::pi * f;
  for (std::size_t t = 0; t < sequence.size(); ++t)
    if (sequence[t] != 0.0) sum += sequence[t] * std::polar(1.0, w * static_cast<double>(t));
  return sum;
}

std::vector<std::complex<double>> padded_dft(std::span<const double> sequence, int size) {
  return plan_for(size).run(sequence);
}

SampledSpectrum seed_grid_spectrum(std::span<const double> sequence) {
  const int length = static_cast<int>(sequence.size());
  const int size = seed_grid_size(length);
  return to_db(padded_dft(sequence, size), size, length);
}

SampledSpectrum circular_spectrum(std::span<const double> sequence) {
  const int length = static_cast<int>(sequence.size());
  return to_db(padded_dft(sequence, length), length, length);
}

SampledSpectrum dense_spectrum(std::span<const double> sequence, int points) {
  // Bins 0..size/2 of a size-point DFT cover 0..0.5 with points samples.
  const int size = 2 * (points - 1);
  const int length = static_cast<int>(sequence.size());
  return to_db(padded_dft(sequence, size), size, length);
}

Minimum dense_minimum_db(std::span<const double> sequence, int points) {
  const SampledSpectrum grid = dense_spectrum(sequence, points);
  const int length = static_cast<int>(sequence.size());
  return minimise_over_frequency(
      grid.db, [&](double f) { return seed_db(std::abs(dtft(sequence, f)), length); });
}

}  // namespace flutterscan::codes
