#pragma once
// Single-precision FFTW plans for real rows of one padded length, shared by
// the row-wise deblurring methods. Plans are made once (planning is not
// thread-safe in FFTW); executing them on any aligned buffer is.

#include <fftw3.h>

#include <complex>
#include <memory>
#include <span>
#include <vector>

namespace flutterscan::imaging {

/// \brief The smallest length >= n whose only prime factors are 2, 3, 5 and 7 (fast in FFTW).
int fast_fft_length(int n);

/// \brief The FFT length for rows of `needed` samples: the smallest multiple of
/// 64 whose quotient is 2-3-5-7 smooth (2048 for a 1080p row and a 52 px blur;
/// 3136 rather than 3087 for a 5 Mpx row).
int row_fft_length(int needed);

/// \brief Bins 0..n/2 of the n-point DFT of `samples` (zero-padded to n; samples
/// past n wrap around), in double precision: sum_t samples[t] e^{-2 pi i j t / n}.
/// One FFT (plan kept per thread and length), not a sum per bin.
std::vector<std::complex<double>> real_dft_bins(std::span<const double> samples, int n);

/// \brief A 64-byte aligned float buffer (what FFTW's SIMD paths want).
class AlignedFloats {
 public:
  AlignedFloats() = default;
  explicit AlignedFloats(std::size_t count)
      : data_(static_cast<float*>(fftwf_malloc(count * sizeof(float)))), size_(count) {}
  float* data() const { return data_.get(); }
  float& operator[](std::size_t i) const { return data_.get()[i]; }
  std::size_t size() const { return size_; }
  std::span<float> span() const { return {data_.get(), size_}; }
  /// \brief The buffer as interleaved complex values.
  std::complex<float>* complex() const {
    return reinterpret_cast<std::complex<float>*>(data_.get());
  }

 private:
  struct Free {
    void operator()(float* p) const { fftwf_free(p); }
  };
  std::unique_ptr<float, Free> data_;
  std::size_t size_ = 0;
};

/// \brief How long FFTW may spend planning: a one-off run estimates (microseconds),
/// a benchmark measures (up to a second, once per length) for plans about 20%
/// faster; a session measures before it streams (measure_row_ffts) and its
/// workers then take the measured plan when there is one, else estimate, so a
/// frame never waits for planning.
enum class PlanEffort { kEstimate, kMeasure, kMeasuredIfKnown };

/// \brief Forward (real to half-complex) and inverse plans of length n.
class RowFft {
 public:
  explicit RowFft(int n, PlanEffort effort = PlanEffort::kEstimate);
  ~RowFft();
  RowFft(const RowFft&) = delete;
  RowFft& operator=(const RowFft&) = delete;

  int length() const { return n_; }
  int bins() const { return n_ / 2 + 1; }
  /// \brief in: n floats; out: bins() complex values (2 * bins() floats). May not alias.
  void forward(const float* in, std::complex<float>* out) const;
  /// \brief in: bins() complex values (destroyed); out: n floats, unnormalised (times n).
  void inverse(std::complex<float>* in, float* out) const;

 private:
  int n_;
  fftwf_plan forward_ = nullptr;
  fftwf_plan inverse_ = nullptr;
};

/// \brief Complex transforms of length n (interleaved std::complex<float>), for
/// two real rows at once: the transform of a + i b. A filter whose impulse
/// response is real applies to both rows as one product with its full-length
/// (Hermitian) spectrum, and the inverse gives the two filtered rows back as the
/// real and imaginary parts. FFTW's interleaved complex transform of a pair
/// costs less than two real-input ones at every length row_fft_length() gives
/// (its split-complex form, used before, only at powers of two up to 2048:
/// docs/algorithms.md, "joint-wiener", rows in pairs). Every array: n complex
/// values from AlignedFloats (2n floats); inputs are not changed and may not
/// alias the outputs.
class RowPairFft {
 public:
  explicit RowPairFft(int n, PlanEffort effort = PlanEffort::kEstimate);
  ~RowPairFft();
  RowPairFft(const RowPairFft&) = delete;
  RowPairFft& operator=(const RowPairFft&) = delete;

  int length() const { return n_; }
  /// \brief out = DFT(in) (sign -1).
  void forward(const std::complex<float>* in, std::complex<float>* out) const;
  /// \brief out = n x inverse DFT(in) (sign +1, unnormalised).
  void inverse(const std::complex<float>* in, std::complex<float>* out) const;

 private:
  int n_;
  fftwf_plan forward_ = nullptr;
  fftwf_plan inverse_ = nullptr;
};

/// \brief Rows a and b (`count` samples each; b null: a row of zeros) into one
/// complex row a + i b, interleaved (2 count floats): RowPairFft's input.
inline void interleave_rows(const float* __restrict a, const float* __restrict b, std::size_t count,
                            float* __restrict pair) {
  if (b == nullptr) {
    for (std::size_t i = 0; i < count; ++i) {
      pair[2 * i] = a[i];
      pair[2 * i + 1] = 0.0f;
    }
    return;
  }
  for (std::size_t i = 0; i < count; ++i) {
    pair[2 * i] = a[i];
    pair[2 * i + 1] = b[i];
  }
}

/// \brief The first a.size() values of an interleaved complex row: the real parts
/// into `a`, the imaginary ones into `b` (empty: not wanted).
inline void deinterleave_rows(const float* __restrict pair, std::span<float> a,
                              std::span<float> b) {
  float* __restrict to_a = a.data();
  if (b.empty()) {
    for (std::size_t i = 0; i < a.size(); ++i) to_a[i] = pair[2 * i];
    return;
  }
  float* __restrict to_b = b.data();
  for (std::size_t i = 0; i < a.size(); ++i) {
    to_a[i] = pair[2 * i];
    to_b[i] = pair[2 * i + 1];
  }
}

/// \brief A RowFft of length n (estimated plan) kept for this thread, as
/// real_dft_bins() keeps its plans: the last few lengths the thread used, so a
/// search called per frame does not plan again (the reference stays valid until
/// the thread asks for four other lengths).
const RowFft& thread_row_fft(int n);

/// \brief Measures FFTW plans (PlanEffort::kMeasure: RowFft and RowPairFft)
/// for rows of `width` samples and PSFs up to `longest_psf` taps: every padded
/// length row_fft_length() gives in that range (usually one or two). FFTW keeps
/// them for the process.
void measure_row_ffts(int width, int longest_psf);

/// \brief out[j] = a[j] * b[j] over `bins` complex values stored as interleaved
/// floats. Written out: std::complex<float> products go through a NaN-checking
/// library call and do not vectorise.
inline void multiply_spectra(const float* __restrict a, const float* __restrict b,
                             float* __restrict out, std::size_t bins) {
  for (std::size_t j = 0; j < 2 * bins; j += 2) {
    out[j] = a[j] * b[j] - a[j + 1] * b[j + 1];
    out[j + 1] = a[j] * b[j + 1] + a[j + 1] * b[j];
  }
}

/// \brief acc[j] += a[j] * b[j] (conjugating a when `conjugate_a`), interleaved floats.
inline void accumulate_spectra(const float* __restrict a, const float* __restrict b,
                               float* __restrict acc, std::size_t bins, bool conjugate_a) {
  const float sign = conjugate_a ? -1.0f : 1.0f;
  for (std::size_t j = 0; j < 2 * bins; j += 2) {
    const float ai = sign * a[j + 1];
    acc[j] += a[j] * b[j] - ai * b[j + 1];
    acc[j + 1] += a[j] * b[j + 1] + ai * b[j];
  }
}

}  // namespace flutterscan::imaging
