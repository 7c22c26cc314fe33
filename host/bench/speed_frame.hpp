#pragma once
// The frame every speed measurement uses: random label-like bars blurred by a
// code and recorded as 8-bit RGB, with its capture model and channel PSFs; and
// the OpenCV baseline a user would write for the same job.

#include <opencv2/core.hpp>

#include <functional>
#include <span>
#include <vector>

#include "imaging/capture_model.hpp"
#include "imaging/joint_wiener.hpp"

namespace flutterscan::bench {

struct SpeedFrame {
  imaging::CaptureModel model;
  cv::Mat rgb8;                           ///< interleaved RGB, 8 bits
  std::vector<imaging::ChannelPsf> psfs;  ///< per channel, noise at a mid-grey signal
};

/// \brief A width x height frame of random bars blurred by `code` over `blur_px`
/// at 3000 e- (cap 3), recorded as 8-bit linear RGB; the belt's speed wandering
/// within the exposure by `block_offsets_px` (CaptureModel; empty: constant).
SpeedFrame make_speed_frame(int width, int height, const LedCode& code, double blur_px,
                            const std::vector<double>& block_offsets_px = {});

/// \brief The row loader for `frame`: one pass over the interleaved row, DN to electrons.
imaging::JointWiener::RowLoader rgb8_row_loader(const SpeedFrame& frame);

/// \brief Median wall time in ms of `repeats` runs of `run`, after one warm-up run.
double median_ms(int repeats, const std::function<void()>& run);

/// \brief The OpenCV way: per channel a 2-D cv::dft Wiener filter on a
/// cv::getOptimalDFTSize padding (filter spectra made once), channels averaged.
class OpenCvWiener {
 public:
  explicit OpenCvWiener(const SpeedFrame& frame);
  /// \brief The fused grey estimate of `rgb8`.
  cv::Mat run(const cv::Mat& rgb8);

 private:
  int rows_, cols_;
  std::vector<cv::Mat> filters_;
  cv::Mat channels_[3], padded_, spectrum_, restored_, sum_;
};

}  // namespace flutterscan::bench
