#pragma once
// The camera settings the linear capture model depends on, through V4L2
// controls: automatic exposure, gain, white balance and dynamic-range
// processing turned off, exposure and gain set, and every value read back.
// A setting that cannot be made is an error naming it; a control the driver
// does not have is a warning (nothing to turn off, but nothing confirmed).

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "flutterscan/common/result.hpp"

namespace flutterscan::capture {

/// \brief Exposure, gain and gamma wanted from the camera; unset = leave as is.
struct V4l2ControlRequest {
  /// Exposure time in microseconds (V4L2_CID_EXPOSURE_ABSOLUTE, 100 us units).
  std::optional<double> exposure_us;
  /// Gain in the driver's units (V4L2_CID_GAIN, else V4L2_CID_ANALOGUE_GAIN).
  std::optional<std::int32_t> gain;
  /// Gamma in the driver's units (V4L2_CID_GAMMA). Which value is linear is
  /// driver-specific (UVC cameras: 100), so it is only set when given.
  std::optional<std::int32_t> gamma;
};

/// \brief One control as read back after setting up.
struct V4l2ControlValue {
  std::uint32_t id = 0;
  std::string name;  ///< The driver's name, e.g. "Gain".
  std::int32_t value = 0;
};

/// \brief What the control setup did.
struct V4l2ControlReport {
  std::vector<V4l2ControlValue> read_back;  ///< Every control touched, in setup order.
  std::vector<std::string> warnings;        ///< Controls that do not exist, so cannot be confirmed.
  std::optional<double> exposure_us;  ///< Exposure read back, when the camera has the control.
  std::optional<std::int32_t> gain;   ///< Gain read back, when the camera has the control.
};

/// \brief Turns off the automatic controls and sets `request` on the open V4L2
/// device `fd` (called `device` in messages), then reads every value back.
/// `raw_sensor_data` (a Bayer format) skips white balance and gamma warnings:
/// raw data passes no colour pipeline.
Result<V4l2ControlReport, std::string> apply_linear_controls(int fd, const std::string& device,
                                                             const V4l2ControlRequest& request,
                                                             bool raw_sensor_data);

/// \brief The controls of the open V4L2 device `fd` that the backend uses, as
/// words for a camera listing: "exposure", "gain", "gamma", "auto exposure",
/// "auto gain", "auto white balance".
std::vector<std::string> v4l2_control_features(int fd);

}  // namespace flutterscan::capture
