#pragma once
// "v4l2:/dev/videoN": the v4l2 backend behind the CameraSource interface. A
// thin adapter over the V4L2 core (v4l2_camera.hpp), which does the device
// work; this file maps settings and formats and copies frames out.
//
// configure(): width/height, pixel format (rgb8 -> RGB24, bgr8 -> BGR24,
// bayer-rggb8 -> SRGGB8, bayer-rggb16 -> SRGGB16, else SRGGB12, else SRGGB10,
// mono8 -> GREY, mono16 -> Y16, yuyv -> YUYV with a warning, mjpeg -> MJPEG
// with a warning; unset: the deepest raw RGGB, then RGB24, BGR24, grey, YUYV,
// MJPEG the device offers), exposure in us, frame rate; auto exposure, auto
// gain, auto white balance off and read back (v4l2_controls.hpp). Refused,
// naming the setting: gain_db (V4L2 gains are in driver units: use the option
// gain=N), any trigger but free-run (V4L2 has no standard trigger control),
// Bayer orders other than RGGB (the pipeline's mosaic layout), and anything
// the driver does not set exactly.
//
// Backend options (CameraContext::options): gain=N and gamma=N in the
// driver's units, io=auto|mmap|userptr, buffers=N (>= 4).
//
// Frames: the driver's 32-bit sequence number extended to 64 bits, the buffer
// timestamp (CLOCK_MONOTONIC on current drivers; a warning says when a driver
// stamps the end of the frame instead of the start of exposure), the bytes
// copied out of the driver buffer. Sequence gaps and buffers the driver
// flagged as broken count as dropped.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "capture/camera_source.hpp"
#include "capture/v4l2_formats.hpp"

namespace flutterscan::capture {

/// \brief The camera on V4L2 node `device` with backend `options` (see above);
/// null with `error` naming the option when an option is malformed.
std::unique_ptr<CameraSource> make_v4l2_camera(
    const std::string& device, const std::vector<std::pair<std::string, std::string>>& options,
    std::string& error);

/// \brief The CameraSource pixel format of a V4L2 format; nothing when the
/// pipeline cannot take it (raw Bayer in another order than RGGB).
std::optional<PixelFormat> pixel_format_of(const V4l2FormatInfo& info);

/// \brief The V4L2 formats that deliver `format`, best first (empty: none).
std::vector<std::uint32_t> fourccs_for(PixelFormat format);

/// \brief Every V4L2 capture node under /dev (video0..video63) the backend can open.
std::vector<CameraInfo> list_v4l2_cameras();

}  // namespace flutterscan::capture
