#include "bench/speed_frame.hpp"

#include <algorithm>
#include <chrono>
#include <random>

#include "sim/forward_model.hpp"

namespace flutterscan::bench {

SpeedFrame make_speed_frame(int width, int height, const LedCode& code, double blur_px,
                            const std::vector<double>& block_offsets_px) {
  SpeedFrame f;
  f.model.code = code;
  f.model.blur_px = blur_px;
  f.model.block_offsets_px = block_offsets_px;
  f.model.led_electrons = imaging::budgeted_led_electrons(code, 3000, 3);
  f.model.bit_depth = 8;
  f.model.full_well = 12000;
  f.model.gain = 12000.0 / 255.0;
  imaging::Plane scene(width, height, 0.35f);
  std::mt19937 rng(1);
  for (int y = height / 10; y < height - height / 10; ++y)
    for (int x = 0; x < width;) {
      const int run = 2 + static_cast<int>(rng() % 6);
      const float value = rng() % 2 ? 0.9f : 0.06f;
      for (int i = 0; i < run && x < width; ++i) scene.at(x++, y) = value;
    }
  const auto dn = sim::record_frame(sim::expected_electrons(scene, f.model), f.model, 1);
  f.rgb8 = cv::Mat(height, width, CV_8UC3);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      for (int c = 0; c < 3; ++c)
        f.rgb8.at<cv::Vec3b>(y, x)[c] =
            static_cast<std::uint8_t>(dn.channels[static_cast<std::size_t>(c)].at(x, y));
  for (int c = 0; c < 3; ++c)
    f.psfs.push_back(
        {imaging::channel_psf(f.model, c), imaging::channel_noise_variance(f.model, 1000)});
  return f;
}

double median_ms(int repeats, const std::function<void()>& run) {
  run();
  std::vector<double> times;
  for (int i = 0; i < repeats; ++i) {
    const auto start = std::chrono::steady_clock::now();
    run();
    times.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
            .count());
  }
  std::nth_element(times.begin(), times.begin() + static_cast<std::ptrdiff_t>(times.size() / 2),
                   times.end());
  return times[times.size() / 2];
}

imaging::JointWiener::RowLoader rgb8_row_loader(const SpeedFrame& frame) {
  const auto gain = static_cast<float>(frame.model.gain);
  const auto offset = static_cast<float>(-frame.model.black_level * frame.model.gain);
  const int width = frame.rgb8.cols;
  const cv::Mat* image = &frame.rgb8;
  // Gain and offset are copied in: read through a reference they would be
  // reloaded every sample and the loop would not vectorise.
  return [image, width, gain, offset](int y, std::span<const std::span<float>> rows) {
    const std::uint8_t* __restrict src = image->ptr<std::uint8_t>(y);
    float* __restrict r = rows[0].data();
    float* __restrict g = rows[1].data();
    float* __restrict b = rows[2].data();
    for (int x = 0; x < width; ++x) {
      r[x] = src[3 * x] * gain + offset;
      g[x] = src[3 * x + 1] * gain + offset;
      b[x] = src[3 * x + 2] * gain + offset;
    }
  };
}

OpenCvWiener::OpenCvWiener(const SpeedFrame& frame)
    : rows_(cv::getOptimalDFTSize(frame.rgb8.rows + 1)),
      cols_(cv::getOptimalDFTSize(frame.rgb8.cols + static_cast<int>(frame.psfs[0].taps.size()))) {
  for (const auto& psf : frame.psfs) {
    cv::Mat kernel = cv::Mat::zeros(rows_, cols_, CV_32F);
    double sum = 0;
    for (double t : psf.taps) sum += t;
    for (std::size_t j = 0; j < psf.taps.size(); ++j)
      kernel.at<float>(0, static_cast<int>(j)) = static_cast<float>(psf.taps[j] / sum);
    cv::Mat spectrum;
    cv::dft(kernel, spectrum, cv::DFT_COMPLEX_OUTPUT);
    cv::Mat planes[2];
    cv::split(spectrum, planes);
    const cv::Mat power = planes[0].mul(planes[0]) + planes[1].mul(planes[1]);
    constexpr double kNoiseToSignal = 0.01;
    const cv::Mat denominator = power + kNoiseToSignal;
    cv::Mat filter_planes[2] = {planes[0] / denominator, -planes[1] / denominator};
    cv::Mat filter;
    cv::merge(filter_planes, 2, filter);
    filters_.push_back(filter);
  }
}

cv::Mat OpenCvWiener::run(const cv::Mat& rgb8) {
  cv::split(rgb8, channels_);
  sum_ = cv::Mat::zeros(rgb8.rows, rgb8.cols, CV_32F);
  for (int c = 0; c < 3; ++c) {
    cv::Mat as_float;
    channels_[c].convertTo(as_float, CV_32F, 1.0 / 255.0);
    cv::copyMakeBorder(as_float, padded_, 0, rows_ - rgb8.rows, 0, cols_ - rgb8.cols,
                       cv::BORDER_REPLICATE);
    cv::dft(padded_, spectrum_, cv::DFT_COMPLEX_OUTPUT);
    cv::mulSpectrums(spectrum_, filters_[static_cast<std::size_t>(c)], spectrum_, 0);
    cv::idft(spectrum_, restored_, cv::DFT_REAL_OUTPUT | cv::DFT_SCALE);
    sum_ += restored_(cv::Rect(0, 0, rgb8.cols, rgb8.rows));
  }
  sum_ /= 3.0;
  return sum_;
}

}  // namespace flutterscan::bench
