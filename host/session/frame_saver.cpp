#include "session/frame_saver.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <utility>

#include "capture/frame_pixels.hpp"

namespace flutterscan::session {

FrameSaver::FrameSaver(SessionFolder& folder, std::size_t queued_bytes)
    : folder_(folder), queued_limit_(queued_bytes), writer_([this] { write_queued(); }) {}

FrameSaver::~FrameSaver() {
  finish();
}

bool FrameSaver::has_room(std::size_t bytes) {
  const std::lock_guard lock(mutex_);
  return room_locked(bytes);
}

bool FrameSaver::room_locked(std::size_t bytes) const {
  return !stopping_ && (frames_.empty() || queued_bytes_ + bytes <= queued_limit_);
}

bool FrameSaver::offer(std::uint64_t sequence, capture::Frame raw, nlohmann::json descriptor,
                       imaging::Plane fused) {
  {
    const std::lock_guard lock(mutex_);
    const std::size_t bytes = bytes_of(raw, fused);
    if (!room_locked(bytes)) return false;
    queued_bytes_ += bytes;
    frames_.push_back({sequence, std::move(raw), std::move(descriptor), std::move(fused)});
  }
  wake_.notify_one();
  return true;
}

std::string FrameSaver::finish() {
  {
    const std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  // What is still queued is written at the usual priority: an idle-priority
  // writer gets no CPU while other processes keep the cores busy, and the
  // session's end would wait for them. (Where the system refuses it, the
  // writer flushes at idle priority.)
  if (writer_.joinable()) {
    sched_param usual{};
    pthread_setschedparam(writer_.native_handle(), SCHED_OTHER, &usual);
  }
  wake_.notify_one();
  if (writer_.joinable()) writer_.join();
  const std::lock_guard lock(mutex_);
  return error_;
}

void FrameSaver::write_queued() {
  // Below the workers: on a loaded line the CPU goes to the frames, and a frame
  // the writer has no time for is not saved (offer() refuses it), not waited for.
  // SCHED_IDLE: the writer runs only on a core no other thread wants, and gives
  // it up at once to a worker that wakes (a nice value still took its share).
  sched_param idle{};
  if (pthread_setschedparam(pthread_self(), SCHED_IDLE, &idle) != 0)
    setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), kWriterNice);
  std::unique_lock lock(mutex_);
  while (true) {
    wake_.wait(lock, [&] { return stopping_ || !frames_.empty(); });
    if (frames_.empty()) return;  // stopping, nothing left
    Frame frame = std::move(frames_.front());
    frames_.pop_front();
    queued_bytes_ -= bytes_of(frame.raw, frame.fused);
    lock.unlock();
    const auto dn = capture::frame_to_dn(frame.raw);
    const std::string error = dn.ok()
                                  ? folder_.save_frame(frame.sequence, dn.value(), frame.descriptor,
                                                       frame.fused.empty() ? nullptr : &frame.fused)
                                  : dn.error();
    lock.lock();
    if (!error.empty() && error_.empty()) error_ = error;
  }
}

}  // namespace flutterscan::session
