#include "imaging/row_fft.hpp"

#include <algorithm>
#include <mutex>

namespace flutterscan::imaging {
namespace {

std::mutex& planner_mutex() {
  static std::mutex mutex;
  return mutex;
}

}  // namespace

int fast_fft_length(int n) {
  for (int m = std::max(1, n);; ++m) {
    int r = m;
    for (int p : {2, 3, 5, 7})
      while (r % p == 0) r /= p;
    if (r == 1) return m;
  }
}

int row_fft_length(int needed) {
  // A multiple of 64 whose quotient is 2-3-5-7 smooth: FFTW's codelets make those
  // fast, while lengths such as 3087 = 3^2 7^3 or 3125 = 5^5 run six times slower.
  constexpr int kBlock = 64;
  for (int m = (std::max(1, needed) + kBlock - 1) / kBlock;; ++m)
    if (fast_fft_length(m) == m) return m * kBlock;
}

RowFft::RowFft(int n, PlanEffort effort) : n_(n) {
  AlignedFloats real(static_cast<std::size_t>(n));
  AlignedFloats spectrum(static_cast<std::size_t>(2 * bins()));
  const std::lock_guard lock(planner_mutex());
  // FFTW_MEASURE overwrites the buffers while planning: they are scratch here.
  const unsigned flags = effort == PlanEffort::kMeasure ? FFTW_MEASURE : FFTW_ESTIMATE;
  forward_ = fftwf_plan_dft_r2c_1d(n, real.data(),
                                   reinterpret_cast<fftwf_complex*>(spectrum.data()), flags);
  inverse_ = fftwf_plan_dft_c2r_1d(n, reinterpret_cast<fftwf_complex*>(spectrum.data()),
                                   real.data(), flags);
}

RowFft::~RowFft() {
  const std::lock_guard lock(planner_mutex());
  fftwf_destroy_plan(forward_);
  fftwf_destroy_plan(inverse_);
}

void RowFft::forward(const float* in, std::complex<float>* out) const {
  fftwf_execute_dft_r2c(forward_, const_cast<float*>(in), reinterpret_cast<fftwf_complex*>(out));
}

void RowFft::inverse(std::complex<float>* in, float* out) const {
  fftwf_execute_dft_c2r(inverse_, reinterpret_cast<fftwf_complex*>(in), out);
}

}  // namespace flutterscan::imaging
