#include "session/frame_preview.hpp"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <vector>

namespace flutterscan::session {

Preview make_preview(std::uint64_t sequence, const imaging::Image& dn, const imaging::Plane& fused,
                     PreviewEncoding encoding) {
  Preview p;
  p.sequence = sequence;
  // Display only: the brightest sample maps to white.
  float brightest = 1;
  for (const auto& plane : dn.channels)
    for (float v : plane.pixels) brightest = std::max(brightest, v);
  const double scale = 255.0 / brightest;
  const int width = dn.width(), height = dn.height();
  const int out_width = std::min(width, 960);
  const double shrink = static_cast<double>(out_width) / width;
  cv::Mat before;
  if (dn.channel_count() == 3) {
    std::vector<cv::Mat> planes;
    for (int c = 2; c >= 0; --c) {
      cv::Mat plane(height, width, CV_32F,
                    const_cast<float*>(dn.channels[static_cast<std::size_t>(c)].pixels.data()));
      cv::Mat bytes;
      plane.convertTo(bytes, CV_8U, scale);
      planes.push_back(bytes);
    }
    cv::merge(planes, before);
  } else {
    cv::Mat plane(height, width, CV_32F, const_cast<float*>(dn.channels[0].pixels.data()));
    plane.convertTo(before, CV_8U, scale);
  }
  cv::Mat latent(fused.height, fused.width, CV_32F, const_cast<float*>(fused.pixels.data()));
  cv::Mat after;
  latent.convertTo(after, CV_8U, 255.0);
  if (shrink < 1) {
    cv::resize(before, before, cv::Size(), shrink, shrink, cv::INTER_AREA);
    cv::resize(after, after, cv::Size(), shrink, shrink, cv::INTER_AREA);
  }
  if (encoding == PreviewEncoding::kJpeg) {
    const std::vector<int> quality = {cv::IMWRITE_JPEG_QUALITY, 85};
    cv::imencode(".jpg", before, p.before, quality);
    cv::imencode(".jpg", after, p.after, quality);
  } else {
    cv::imencode(".png", before, p.before);
    cv::imencode(".png", after, p.after);
  }
  return p;
}

}  // namespace flutterscan::session
