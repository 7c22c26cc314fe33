#include "session/live_view_pictures.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <ctime>

#include <utility>

#include "capture/frame_pixels.hpp"
#include "session/frame_preview.hpp"

namespace flutterscan::session {

namespace {

/// CPU time of this thread, ms.
double thread_cpu_ms() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) * 1e3 + static_cast<double>(t.tv_nsec) * 1e-6;
}

/// Every `step`-th pixel of `frame` along both axes (every `step`-th 2x2 cell of
/// a Bayer mosaic, which keeps its pattern): a picture `step` times narrower made
/// from step^2 times fewer samples. YUYV and MJPEG frames come back whole.
capture::Frame thinned(const capture::Frame& frame, int step) {
  const capture::PixelFormat format = frame.format.pixel_format;
  const int bytes = capture::bytes_per_pixel(format);
  if (step <= 1 || bytes == 0 || format == capture::PixelFormat::kYuyv) return frame;
  const bool bayer = capture::is_bayer_mosaic(format);
  const int cell = bayer ? 2 : 1;
  auto kept = [&](int length) {
    std::vector<int> at;
    for (int i = 0; i < length; i += cell * step)
      for (int j = 0; j < cell && i + j < length; ++j) at.push_back(i + j);
    return at;
  };
  const std::vector<int> columns = kept(frame.format.width), rows = kept(frame.format.height);
  const std::size_t stride = frame.format.row_bytes > 0
                                 ? frame.format.row_bytes
                                 : static_cast<std::size_t>(frame.format.width) * bytes;
  capture::Frame out;
  out.sequence = frame.sequence;
  out.format = frame.format;
  out.format.width = static_cast<int>(columns.size());
  out.format.height = static_cast<int>(rows.size());
  out.format.row_bytes = 0;
  out.data.resize(columns.size() * rows.size() * static_cast<std::size_t>(bytes));
  if (frame.data.size() < stride * static_cast<std::size_t>(frame.format.height)) return frame;
  std::uint8_t* to = out.data.data();
  for (const int y : rows) {
    const std::uint8_t* row = frame.data.data() + stride * static_cast<std::size_t>(y);
    for (const int x : columns) {
      std::copy_n(row + static_cast<std::size_t>(x) * bytes, bytes, to);
      to += bytes;
    }
  }
  return out;
}

/// `plane` resized to `width` x `height` (area average).
imaging::Plane resized(const imaging::Plane& plane, int width, int height) {
  if (plane.width == width && plane.height == height) return plane;
  imaging::Plane out(width, height);
  const cv::Mat from(plane.height, plane.width, CV_32F, const_cast<float*>(plane.pixels.data()));
  cv::Mat to(height, width, CV_32F, out.pixels.data());
  cv::resize(from, to, to.size(), 0, 0, cv::INTER_AREA);
  return out;
}

}  // namespace

LivePictures::LivePictures(int max_width) : max_width_(max_width), thread_([this] { run(); }) {}

LivePictures::~LivePictures() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  changed_.notify_all();
  thread_.join();
}

bool LivePictures::idle() const {
  std::lock_guard lock(mutex_);
  return !busy_ && !pending_;
}

void LivePictures::encode(capture::Frame frame, imaging::Plane latent, nlohmann::json about) {
  {
    std::lock_guard lock(mutex_);
    pending_ = Job{std::move(frame), std::move(latent), std::move(about)};
  }
  changed_.notify_all();
}

std::shared_ptr<const LivePicture> LivePictures::latest() const {
  std::lock_guard lock(mutex_);
  return kept_.empty() ? nullptr : kept_.back();
}

std::shared_ptr<const LivePicture> LivePictures::of_frame(std::uint64_t sequence) const {
  std::lock_guard lock(mutex_);
  for (const auto& picture : kept_)
    if (picture->sequence == sequence) return picture;
  return nullptr;
}

std::uint64_t LivePictures::encoded() const {
  std::lock_guard lock(mutex_);
  return encoded_;
}

double LivePictures::encode_cpu_ms() const {
  std::lock_guard lock(mutex_);
  return encode_cpu_ms_;
}

void LivePictures::wait_idle() const {
  std::unique_lock lock(mutex_);
  changed_.wait(lock, [this] { return stopping_ || (!busy_ && !pending_); });
}

void LivePictures::run() {
  // Below the workers: a picture may wait, a frame may not.
  setpriority(PRIO_PROCESS, static_cast<id_t>(gettid()), 10);
  std::unique_lock lock(mutex_);
  for (;;) {
    changed_.wait(lock, [this] { return stopping_ || pending_.has_value(); });
    if (stopping_) return;
    Job job = std::move(*pending_);
    pending_.reset();
    busy_ = true;
    lock.unlock();
    const double cpu_start = thread_cpu_ms();
    std::shared_ptr<LivePicture> picture;
    // Thinned before it is converted: a picture costs about the same at any frame size.
    const int step = (job.frame.format.width + max_width_ - 1) / max_width_;
    if (const auto dn = capture::frame_to_dn(thinned(job.frame, step)); dn.ok()) {
      Preview preview = make_preview(job.frame.sequence, dn.value(),
                                     resized(job.latent, dn.value().width(), dn.value().height()),
                                     PreviewEncoding::kJpeg);
      picture = std::make_shared<LivePicture>();
      picture->sequence = job.frame.sequence;
      picture->width = job.latent.width;
      picture->height = job.latent.height;
      picture->captured_jpeg = std::move(preview.before);
      picture->fused_jpeg = std::move(preview.after);
      picture->about = std::move(job.about);
    }
    const double cpu_ms = thread_cpu_ms() - cpu_start;
    lock.lock();
    encode_cpu_ms_ += cpu_ms;
    if (picture) {
      kept_.push_back(std::move(picture));
      if (kept_.size() > kKept) kept_.pop_front();
      ++encoded_;
    }
    busy_ = false;
    changed_.notify_all();
  }
}

}  // namespace flutterscan::session
