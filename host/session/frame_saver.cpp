#include "session/frame_saver.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <utility>

namespace flutterscan::session {

FrameSaver::FrameSaver(SessionFolder& folder, std::size_t queued)
    : folder_(folder), queued_(queued), writer_([this] { write_queued(); }) {}

FrameSaver::~FrameSaver() {
  finish();
}

bool FrameSaver::has_room() {
  const std::lock_guard lock(mutex_);
  return room_locked();
}

bool FrameSaver::room_locked() const {
  return !stopping_ && frames_.size() < queued_;
}

bool FrameSaver::offer(std::uint64_t sequence, imaging::Image dn, nlohmann::json descriptor,
                       imaging::Plane fused) {
  {
    const std::lock_guard lock(mutex_);
    if (!room_locked()) return false;
    frames_.push_back({sequence, std::move(dn), std::move(descriptor), std::move(fused)});
  }
  wake_.notify_one();
  return true;
}

std::string FrameSaver::finish() {
  {
    const std::lock_guard lock(mutex_);
    stopping_ = true;
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
    lock.unlock();
    const std::string error = folder_.save_frame(frame.sequence, frame.dn, frame.descriptor,
                                                 frame.fused.empty() ? nullptr : &frame.fused);
    lock.lock();
    if (!error.empty() && error_.empty()) error_ = error;
  }
}

}  // namespace flutterscan::session
