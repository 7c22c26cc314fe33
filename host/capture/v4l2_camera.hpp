#pragma once
// The V4L2 camera core: one capture device opened non-blocking, its format set
// so the colour channels stay apart, its automatic controls turned off, and
// frames streamed through MMAP buffers (USERPTR where mmap is unavailable)
// with their sequence numbers and timestamps. Dropped frames are counted from
// gaps in the driver's sequence numbers.
//
// Deliberately small: POSIX and <linux/videodev2.h> only (no OpenCV, no
// imaging code), so it also builds into the static test program that runs
// inside the vivid VM test. Converting pixels is someone else's job.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "capture/v4l2_controls.hpp"
#include "capture/v4l2_formats.hpp"
#include "flutterscan/common/result.hpp"

namespace flutterscan::capture {

/// \brief How buffers are shared with the driver.
enum class V4l2IoMethod {
  kAuto,     ///< MMAP, falling back to USERPTR when mmap is unavailable.
  kMmap,     ///< Driver-allocated buffers mapped into this process.
  kUserPtr,  ///< Buffers allocated here, handed to the driver by address.
};

/// \brief "auto", "mmap" or "userptr".
const char* v4l2_io_method_name(V4l2IoMethod method);

/// \brief Everything asked of an open camera by configure().
struct V4l2Config {
  int width = 0;   ///< 0: keep the driver's current width.
  int height = 0;  ///< 0: keep the driver's current height.
  /// Wanted pixel formats, the first one the device offers wins; empty: the
  /// first of v4l2_accepted_formats() the device offers.
  std::vector<std::uint32_t> fourccs;
  double frame_rate = 0.0;  ///< Frames per second; 0: leave as is.
  V4l2ControlRequest controls;
  int buffer_count = 4;  ///< Buffers requested (the driver may give more); at least 4.
  V4l2IoMethod io = V4l2IoMethod::kAuto;
};

/// \brief Which clock a buffer timestamp is on (V4L2_BUF_FLAG_TIMESTAMP_*).
enum class V4l2Clock { kUnknown, kMonotonic, kCopy };
/// \brief Which moment of the exposure the timestamp marks (V4L2_BUF_FLAG_TSTAMP_SRC_*).
enum class V4l2TimestampSource { kEndOfFrame, kStartOfExposure };

/// \brief What next_frame() got.
enum class V4l2Wait { kFrame, kTimeout, kError };

/// \brief One captured frame. `data` points into a driver buffer that stays
/// valid until the next call to next_frame() or stop().
struct V4l2Frame {
  std::span<const std::uint8_t> data;  ///< bytesused bytes of the image.
  std::uint32_t sequence = 0;          ///< The driver's frame counter.
  std::int64_t timestamp_ns = 0;       ///< Buffer timestamp, on `clock`.
  V4l2Clock clock = V4l2Clock::kUnknown;
  V4l2TimestampSource timestamp_source = V4l2TimestampSource::kEndOfFrame;
  std::uint32_t dropped_before = 0;  ///< Sequence numbers skipped just before this frame.
  std::uint64_t index = 0;           ///< Frames delivered before this one.
};

/// \brief The negotiated format.
struct V4l2Format {
  V4l2FormatInfo info;
  int width = 0;
  int height = 0;
  std::uint32_t bytes_per_line = 0;
  std::uint32_t image_size = 0;
  double frame_rate = 0.0;  ///< As read back; 0 when the driver does not report it.
};

/// \brief What the device is and what was set up on it.
struct V4l2Description {
  std::string driver, card, bus_info;
  std::vector<std::uint32_t> offered_fourccs;  ///< Every format ENUM_FMT listed.
  V4l2Format format;
  V4l2ControlReport controls;
  std::vector<std::string> warnings;  ///< Format and I/O warnings (controls' are in `controls`).
};

/// \brief Counters kept while streaming.
struct V4l2Stats {
  std::uint64_t frames = 0;   ///< Frames delivered.
  std::uint64_t dropped = 0;  ///< Sequence numbers never delivered (gaps).
  std::uint64_t corrupt = 0;  ///< Buffers the driver flagged as errors or short, skipped.
};

/// \brief An open V4L2 capture device (see the file comment).
class V4l2Camera {
 public:
  /// \brief Opens `device` non-blocking, checks it can capture and stream
  /// (VIDIOC_QUERYCAP) and lists its formats (VIDIOC_ENUM_FMT).
  static Result<std::unique_ptr<V4l2Camera>, std::string> open(const std::string& device);

  ~V4l2Camera();
  V4l2Camera(const V4l2Camera&) = delete;
  V4l2Camera& operator=(const V4l2Camera&) = delete;

  /// \brief Sets the format, frame rate and controls and reads them back.
  /// Refuses (error message naming the setting and device; empty = success)
  /// anything it cannot set exactly. Not while streaming.
  std::string configure(const V4l2Config& config);

  const std::string& device() const { return device_; }
  const V4l2Description& description() const { return description_; }
  /// \brief Which controls the device has, as words for a camera listing
  /// (v4l2_control_features).
  std::vector<std::string> control_features() const;
  /// \brief The buffer sharing in use once started (kAuto before start()).
  V4l2IoMethod io_method() const { return io_in_use_; }
  const V4l2Stats& stats() const { return stats_; }

  /// \brief Allocates the buffers, queues them and starts streaming (after
  /// configure()). An empty string on success, else the reason.
  std::string start();
  /// \brief Waits at most `timeout_ms` for the next good frame; the previous
  /// frame's buffer goes back to the driver first. kError sets `error`.
  V4l2Wait next_frame(V4l2Frame& frame, int timeout_ms, std::string& error);
  /// \brief Stops streaming and frees the buffers; safe to call twice.
  void stop();

 private:
  struct Buffer {
    std::uint8_t* start = nullptr;
    std::size_t length = 0;
    bool mapped = false;  ///< mmap'ed (else allocated here for USERPTR).
  };

  V4l2Camera(int fd, std::string device) : fd_(fd), device_(std::move(device)) {}
  std::string negotiate_format();
  std::string set_frame_rate();
  std::string request_mmap_buffers();
  std::string request_userptr_buffers();
  std::string queue_buffer(std::uint32_t index);
  void release_buffers();

  int fd_ = -1;
  std::string device_;
  V4l2Config config_;
  bool configured_ = false;
  V4l2Description description_;
  V4l2IoMethod io_in_use_ = V4l2IoMethod::kAuto;
  std::vector<Buffer> buffers_;
  std::optional<std::uint32_t> driver_memory_;  ///< V4L2_MEMORY_* the driver holds buffers of.
  bool streaming_ = false;
  std::optional<std::uint32_t> held_buffer_;  ///< Index of the buffer behind the last frame.
  std::optional<std::uint32_t> last_sequence_;
  V4l2Stats stats_;
};

}  // namespace flutterscan::capture
