#include "imaging/row_fft.hpp"

#include <algorithm>
#include <memory>
#include <mutex>

namespace flutterscan::imaging {
namespace {

std::mutex& planner_mutex() {
  static std::mutex mutex;
  return mutex;
}

/// A double-precision forward plan of one length with its own aligned buffers,
/// made once per thread and length in use (planning holds the planner lock).
class DoublePlan {
 public:
  explicit DoublePlan(int n)
      : n_(n),
        in_(static_cast<double*>(fftw_malloc(sizeof(double) * static_cast<std::size_t>(n)))),
        out_(static_cast<fftw_complex*>(
            fftw_malloc(sizeof(fftw_complex) * static_cast<std::size_t>(n / 2 + 1)))) {
    const std::lock_guard lock(planner_mutex());
    plan_ = fftw_plan_dft_r2c_1d(n, in_, out_, FFTW_ESTIMATE);
  }
  ~DoublePlan() {
    {
      const std::lock_guard lock(planner_mutex());
      fftw_destroy_plan(plan_);
    }
    fftw_free(in_);
    fftw_free(out_);
  }
  DoublePlan(const DoublePlan&) = delete;
  DoublePlan& operator=(const DoublePlan&) = delete;

  int length() const { return n_; }
  std::vector<std::complex<double>> transform(std::span<const double> samples) {
    std::fill(in_, in_ + n_, 0.0);
    for (std::size_t t = 0; t < samples.size(); ++t)
      in_[t % static_cast<std::size_t>(n_)] += samples[t];
    fftw_execute(plan_);
    std::vector<std::complex<double>> bins(static_cast<std::size_t>(n_ / 2 + 1));
    for (std::size_t j = 0; j < bins.size(); ++j) bins[j] = {out_[j][0], out_[j][1]};
    return bins;
  }

 private:
  int n_;
  double* in_;
  fftw_complex* out_;
  fftw_plan plan_ = nullptr;
};

}  // namespace

std::vector<std::complex<double>> real_dft_bins(std::span<const double> samples, int n) {
  // The last few lengths this thread used (a frame's rows, a blur search's rows).
  thread_local std::vector<std::unique_ptr<DoublePlan>> plans;
  auto it =
      std::find_if(plans.begin(), plans.end(), [n](const auto& p) { return p->length() == n; });
  if (it == plans.end()) {
    if (plans.size() >= 4) plans.erase(plans.begin());
    plans.push_back(std::make_unique<DoublePlan>(n));
    it = plans.end() - 1;
  }
  return (*it)->transform(samples);
}

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
  auto make = [&](unsigned flags) {
    forward_ = fftwf_plan_dft_r2c_1d(n, real.data(),
                                     reinterpret_cast<fftwf_complex*>(spectrum.data()), flags);
    inverse_ = fftwf_plan_dft_c2r_1d(n, reinterpret_cast<fftwf_complex*>(spectrum.data()),
                                     real.data(), flags);
  };
  if (effort == PlanEffort::kMeasuredIfKnown) {
    make(FFTW_MEASURE | FFTW_WISDOM_ONLY);  // no plan (null) unless measured before
    if (forward_ != nullptr && inverse_ != nullptr) return;
    if (forward_ != nullptr) fftwf_destroy_plan(forward_);
    if (inverse_ != nullptr) fftwf_destroy_plan(inverse_);
  }
  make(effort == PlanEffort::kMeasure ? FFTW_MEASURE : FFTW_ESTIMATE);
}

const RowFft& thread_row_fft(int n) {
  thread_local std::vector<std::unique_ptr<RowFft>> plans;
  auto it =
      std::find_if(plans.begin(), plans.end(), [n](const auto& p) { return p->length() == n; });
  if (it != plans.end()) return **it;
  if (plans.size() >= 4) plans.erase(plans.begin());
  plans.push_back(std::make_unique<RowFft>(n));
  return *plans.back();
}

void measure_row_ffts(int width, int longest_psf) {
  int measured = 0;
  for (int taps = 1; taps <= longest_psf; ++taps) {
    const int n = row_fft_length(width + taps);
    if (n != measured) {
      const RowFft plans(n, PlanEffort::kMeasure);
      const RowPairFft pair(n, PlanEffort::kMeasure);
    }
    measured = n;
  }
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

RowPairFft::RowPairFft(int n, PlanEffort effort) : n_(n) {
  const auto floats = 2 * static_cast<std::size_t>(n);
  AlignedFloats in(floats), out(floats);
  auto* in_complex = reinterpret_cast<fftwf_complex*>(in.data());
  auto* out_complex = reinterpret_cast<fftwf_complex*>(out.data());
  const std::lock_guard lock(planner_mutex());
  // FFTW_MEASURE overwrites the buffers while planning: they are scratch here.
  auto make = [&](unsigned flags) {
    forward_ = fftwf_plan_dft_1d(n, in_complex, out_complex, FFTW_FORWARD, flags);
    inverse_ = fftwf_plan_dft_1d(n, in_complex, out_complex, FFTW_BACKWARD, flags);
  };
  if (effort == PlanEffort::kMeasuredIfKnown) {
    make(FFTW_MEASURE | FFTW_WISDOM_ONLY);  // no plan (null) unless measured before
    if (forward_ != nullptr && inverse_ != nullptr) return;
    if (forward_ != nullptr) fftwf_destroy_plan(forward_);
    if (inverse_ != nullptr) fftwf_destroy_plan(inverse_);
  }
  make(effort == PlanEffort::kMeasure ? FFTW_MEASURE : FFTW_ESTIMATE);
}

RowPairFft::~RowPairFft() {
  const std::lock_guard lock(planner_mutex());
  fftwf_destroy_plan(forward_);
  fftwf_destroy_plan(inverse_);
}

void RowPairFft::forward(const std::complex<float>* in, std::complex<float>* out) const {
  // An out-of-place complex transform leaves its input as it was (FFTW's default).
  fftwf_execute_dft(forward_,
                    reinterpret_cast<fftwf_complex*>(const_cast<std::complex<float>*>(in)),
                    reinterpret_cast<fftwf_complex*>(out));
}

void RowPairFft::inverse(const std::complex<float>* in, std::complex<float>* out) const {
  fftwf_execute_dft(inverse_,
                    reinterpret_cast<fftwf_complex*>(const_cast<std::complex<float>*>(in)),
                    reinterpret_cast<fftwf_complex*>(out));
}

}  // namespace flutterscan::imaging
