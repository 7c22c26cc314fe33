#include "session/live_view_pictures.hpp"

#include <sys/resource.h>
#include <unistd.h>

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
    if (const auto dn = capture::frame_to_dn(job.frame); dn.ok()) {
      Preview preview = make_preview(job.frame.sequence, dn.value(), job.latent, max_width_);
      picture = std::make_shared<LivePicture>();
      picture->sequence = job.frame.sequence;
      picture->width = job.latent.width;
      picture->height = job.latent.height;
      picture->captured_png = std::move(preview.before_png);
      picture->fused_png = std::move(preview.after_png);
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
