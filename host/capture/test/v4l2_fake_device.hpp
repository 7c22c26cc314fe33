#pragma once
// A fake V4L2 capture device for the v4l2 backend's tests: a umockdev testbed
// holding /dev/video0 whose ioctls are answered by this class (umockdev's
// custom ioctl handler API), so the backend's real open/ioctl calls reach it
// through umockdev's preload library. The process must run under
// umockdev-wrapper (v4l2_fake_device_main.cpp re-executes itself under it).
//
// What it models: QUERYCAP, ENUM_FMT, G/S_FMT (size clamped to a maximum,
// unknown formats replaced by the first one, as drivers do), G/S_PARM with a
// fixed list of frame rates, QUERYCTRL/G_CTRL/S_CTRL with auto-exposure
// making manual exposure busy, REQBUFS/QUERYBUF for MMAP and USERPTR,
// QBUF/DQBUF/STREAMON/STREAMOFF. A dequeued USERPTR buffer is filled with a
// pattern derived from its sequence number (see pattern_byte), stamped with
// a monotonic start-of-exposure timestamp, and the sequence can jump
// (dropped frames) or a buffer carry V4L2_BUF_FLAG_ERROR, as configured.
// Limits of umockdev: mmap() on the node fails (ENODEV) and poll() never
// reports readiness, so streaming is USERPTR only.

#include <linux/videodev2.h>

#include <cstdint>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <vector>

struct _UMockdevTestbed;
struct _UMockdevIoctlBase;
struct _UMockdevIoctlClient;
struct _UMockdevIoctlData;

namespace flutterscan::capture::testing {

/// \brief One control of the fake device.
struct FakeControl {
  std::uint32_t id = 0;
  std::string name;
  std::uint32_t type = V4L2_CTRL_TYPE_INTEGER;
  std::int32_t minimum = 0, maximum = 255, step = 1, default_value = 0;
  std::int32_t value = 0;
  bool ignores_writes = false;  ///< S_CTRL succeeds but the value stays (a stuck control).
};

/// \brief How the fake device behaves.
struct FakeDeviceConfig {
  std::string card = "Fake V4L2 camera";
  std::uint32_t device_caps = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_STREAMING;
  std::vector<std::uint32_t> formats{V4L2_PIX_FMT_SRGGB10, V4L2_PIX_FMT_RGB24, V4L2_PIX_FMT_YUYV};
  int max_width = 1920, max_height = 1080;
  int initial_width = 64, initial_height = 48;
  std::vector<std::uint32_t> frame_rates{30, 15, 5};  ///< Empty: no V4L2_CAP_TIMEPERFRAME.
  std::vector<FakeControl> controls = default_controls();
  bool userptr_supported = true;
  /// Before delivering the frame with this delivery index, skip that many sequence numbers.
  std::map<std::uint64_t, std::uint32_t> sequence_gaps;
  /// Delivery indices whose buffer carries V4L2_BUF_FLAG_ERROR.
  std::set<std::uint64_t> error_frames;
  /// After this many delivered frames DQBUF only says EAGAIN (a stalled camera).
  std::optional<std::uint64_t> stall_after;
  std::int64_t frame_interval_ns = 33'333'333;

  /// \brief A UVC-like set: auto exposure (menu, on), exposure (100 us units),
  /// auto gain (on), gain, auto white balance (on), gamma.
  static std::vector<FakeControl> default_controls();
};

/// \brief The byte at `offset` of the frame with sequence number `sequence`.
std::uint8_t pattern_byte(std::uint32_t sequence, std::size_t offset);

/// \brief The fake device, live while this object is (see the file comment).
class FakeV4l2Device {
 public:
  explicit FakeV4l2Device(FakeDeviceConfig config);
  ~FakeV4l2Device();
  FakeV4l2Device(const FakeV4l2Device&) = delete;
  FakeV4l2Device& operator=(const FakeV4l2Device&) = delete;

  /// \brief The node to open: "/dev/video0".
  std::string path() const { return "/dev/video0"; }
  /// \brief A control's current value, as the device holds it.
  std::optional<std::int32_t> control_value(std::uint32_t id) const;
  /// \brief How often REQBUFS asked for buffers (count > 0) of `memory` (V4L2_MEMORY_*).
  int buffer_requests(std::uint32_t memory) const;
  bool streaming() const;

  /// \brief The ioctl handler (public for the C callback; not for tests).
  bool handle(_UMockdevIoctlClient* client);

 private:
  struct QueuedBuffer {
    std::uint32_t index;
    unsigned long userptr;
    std::uint32_t length;
  };
  long answer(unsigned long request, void* arg, _UMockdevIoctlData* data, int& error);
  long dequeue(v4l2_buffer& buffer, _UMockdevIoctlData* data, int& error);
  void set_format(v4l2_pix_format& pix);

  FakeDeviceConfig config_;
  mutable std::mutex mutex_;
  _UMockdevTestbed* testbed_ = nullptr;
  _UMockdevIoctlBase* handler_ = nullptr;
  v4l2_pix_format format_{};
  std::uint32_t frame_rate_ = 30;
  std::uint32_t memory_ = 0;
  std::uint32_t buffer_count_ = 0;
  std::vector<QueuedBuffer> queue_;
  bool streaming_ = false;
  std::uint64_t delivered_ = 0;
  std::uint32_t next_sequence_ = 0;
  std::map<std::uint32_t, int> buffer_requests_;
};

}  // namespace flutterscan::capture::testing
