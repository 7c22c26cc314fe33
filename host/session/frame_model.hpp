#pragma once
// The capture descriptor of a matched frame, built from its exposure event
// and the session's calibration: the code that lit it (by the event's code id),
// the blur from the encoder (|encoder_delta| x px_per_count; a negative delta
// reverses the direction), crosstalk, light level and the camera's noise.

#include <string>

#include "capture/camera_source.hpp"
#include "flutterscan/common/result.hpp"
#include "imaging/capture_model.hpp"
#include "session/frame_matcher.hpp"
#include "session/session_config.hpp"

namespace flutterscan::session {

/// \brief The model of a frame of `format` lit as `event` says, with `code` the
/// code uploaded under the event's code id. Error names the mismatch (slot
/// count, pixel format).
Result<imaging::CaptureModel, std::string> frame_model(const ExposureRecord& event,
                                                       const LedCode& code,
                                                       const SessionConfig& config,
                                                       const capture::FrameFormat& format);

/// \brief The blur `event` implies on a frame of `format` when it is out of range,
/// as a message naming the encoder counts, optics.px_per_count, the blur and the
/// range [0, min(frame along the motion - 1, imaging::kMaxBlurPx)]; empty if in
/// range. The session flags such a frame `blur-out-of-range` and goes on.
std::string blur_out_of_range(const ExposureRecord& event, const OpticsConfig& optics,
                              const capture::FrameFormat& format);

/// \brief Belt speed during the exposure, image pixels per controller microsecond:
/// from the encoder, or (optics.encoder = false) the nominal blur over the exposure.
double belt_speed_px_per_us(const ExposureRecord& event, const OpticsConfig& optics);

}  // namespace flutterscan::session
