#include "capture/v4l2_controls.hpp"

#include <linux/videodev2.h>
#include <sys/ioctl.h>

#include <cerrno>
#include <cmath>
#include <cstring>

#include "capture/v4l2_ioctl.hpp"

namespace flutterscan::capture {
namespace {

using Report = Result<V4l2ControlReport, std::string>;

/// A control the driver has and has not disabled.
struct Control {
  v4l2_queryctrl query{};
  std::string name() const { return reinterpret_cast<const char*>(query.name); }
};

std::optional<Control> find_control(int fd, std::uint32_t id) {
  Control control;
  control.query.id = id;
  if (v4l2_ioctl(fd, VIDIOC_QUERYCTRL, &control.query) != 0) return std::nullopt;
  if (control.query.flags & V4L2_CTRL_FLAG_DISABLED) return std::nullopt;
  return control;
}

std::optional<std::int32_t> read_control(int fd, std::uint32_t id) {
  v4l2_control value{};
  value.id = id;
  if (v4l2_ioctl(fd, VIDIOC_G_CTRL, &value) != 0) return std::nullopt;
  return value.value;
}

/// Sets `control` to `wanted` (unless it already is) and reads it back; an
/// error message naming `what` when either fails or the value differs.
std::optional<std::string> set_and_verify(int fd, const std::string& device, const Control& control,
                                          std::int32_t wanted, const std::string& what,
                                          V4l2ControlReport& report) {
  const std::optional<std::int32_t> before = read_control(fd, control.query.id);
  if (!before || *before != wanted) {
    v4l2_control value{};
    value.id = control.query.id;
    value.value = wanted;
    if (v4l2_ioctl(fd, VIDIOC_S_CTRL, &value) != 0) {
      return device + ": cannot set " + what + " (control \"" + control.name() + "\") to " +
             std::to_string(wanted) + ": " + std::strerror(errno);
    }
  }
  const std::optional<std::int32_t> after = read_control(fd, control.query.id);
  if (!after) {
    return device + ": cannot read back " + what + " (control \"" + control.name() +
           "\"): " + std::strerror(errno);
  }
  if (*after != wanted) {
    return device + ": " + what + " (control \"" + control.name() + "\") set to " +
           std::to_string(wanted) + " but reads back " + std::to_string(*after);
  }
  report.read_back.push_back({control.query.id, control.name(), *after});
  return std::nullopt;
}

/// Checks `value` against the control's range and step; an error naming `what` if outside.
std::optional<std::string> check_range(const std::string& device, const Control& control,
                                       std::int64_t value, const std::string& what,
                                       const std::string& shown) {
  const v4l2_queryctrl& q = control.query;
  if (value < q.minimum || value > q.maximum) {
    return device + ": " + what + " " + shown + " is outside the camera's range " +
           std::to_string(q.minimum) + ".." + std::to_string(q.maximum) + " (control \"" +
           control.name() + "\")";
  }
  if (q.step > 1 && (value - q.minimum) % q.step != 0) {
    return device + ": " + what + " " + shown + " is not a multiple of the control's step " +
           std::to_string(q.step) + " from " + std::to_string(q.minimum);
  }
  return std::nullopt;
}

/// An automatic control to turn off: its id, what it is called in messages, its off value.
struct AutoControl {
  std::uint32_t id;
  const char* what;
  std::int32_t off;
};

}  // namespace

Result<V4l2ControlReport, std::string> apply_linear_controls(int fd, const std::string& device,
                                                             const V4l2ControlRequest& request,
                                                             bool raw_sensor_data) {
  V4l2ControlReport report;

  // Automatic controls first: while they are on, manual values are inactive.
  const AutoControl exposure_autos[] = {
      {V4L2_CID_EXPOSURE_AUTO, "auto exposure", V4L2_EXPOSURE_MANUAL},
      {V4L2_CID_EXPOSURE_AUTO_PRIORITY, "auto exposure priority (frame rate may vary)", 0},
  };
  const AutoControl other_autos[] = {
      {V4L2_CID_AUTOGAIN, "auto gain", 0},
      {V4L2_CID_AUTO_WHITE_BALANCE, "auto white balance", 0},
      {V4L2_CID_AUTO_N_PRESET_WHITE_BALANCE, "white balance preset", V4L2_WHITE_BALANCE_MANUAL},
      {V4L2_CID_WIDE_DYNAMIC_RANGE, "wide dynamic range", 0},
  };
  bool has_auto_exposure = false;
  for (const AutoControl& a : exposure_autos) {
    if (const auto control = find_control(fd, a.id)) {
      has_auto_exposure = true;
      if (auto error = set_and_verify(fd, device, *control, a.off, a.what, report)) {
        return Report::failure(*error);
      }
    }
  }
  if (!has_auto_exposure) {
    report.warnings.push_back(device + ": no auto exposure control; cannot confirm it is off");
  }
  bool has_autogain = false;
  bool has_white_balance = false;
  for (const AutoControl& a : other_autos) {
    if (const auto control = find_control(fd, a.id)) {
      if (a.id == V4L2_CID_AUTOGAIN) has_autogain = true;
      if (a.id != V4L2_CID_AUTOGAIN && a.id != V4L2_CID_WIDE_DYNAMIC_RANGE)
        has_white_balance = true;
      if (auto error = set_and_verify(fd, device, *control, a.off, a.what, report)) {
        return Report::failure(*error);
      }
    }
  }
  if (!has_autogain) {
    report.warnings.push_back(device + ": no auto gain control; cannot confirm it is off");
  }
  if (!has_white_balance && !raw_sensor_data) {
    report.warnings.push_back(device + ": no auto white balance control; cannot confirm it is off");
  }

  // Gamma: the linear value is driver-specific, so set only when asked.
  if (const auto gamma = find_control(fd, V4L2_CID_GAMMA)) {
    if (request.gamma) {
      const std::string shown = std::to_string(*request.gamma);
      if (auto error = check_range(device, *gamma, *request.gamma, "gamma", shown)) {
        return Report::failure(*error);
      }
      if (auto error = set_and_verify(fd, device, *gamma, *request.gamma, "gamma", report)) {
        return Report::failure(*error);
      }
    } else {
      const std::int32_t now =
          read_control(fd, V4L2_CID_GAMMA).value_or(gamma->query.default_value);
      report.warnings.push_back(device + ": gamma control present (now " + std::to_string(now) +
                                ", range " + std::to_string(gamma->query.minimum) + ".." +
                                std::to_string(gamma->query.maximum) +
                                "); its linear value is driver-specific: set gamma explicitly");
    }
  } else if (request.gamma) {
    return Report::failure(device + ": gamma requested but the driver has no gamma control");
  } else if (!raw_sensor_data) {
    report.warnings.push_back(device +
                              ": no gamma control; cannot confirm the tone curve is linear");
  }

  // Exposure in 100 us units.
  if (const auto exposure = find_control(fd, V4L2_CID_EXPOSURE_ABSOLUTE)) {
    if (request.exposure_us) {
      const double units = *request.exposure_us / 100.0;
      const auto wanted = static_cast<std::int64_t>(std::llround(units));
      const std::string shown = std::to_string(*request.exposure_us) + " us";
      if (!(*request.exposure_us > 0.0) || std::abs(units - static_cast<double>(wanted)) > 1e-6) {
        return Report::failure(device + ": exposure " + shown +
                               " is not a positive multiple of the camera's 100 us unit");
      }
      if (auto error = check_range(device, *exposure, wanted, "exposure", shown)) {
        return Report::failure(*error);
      }
      if (auto error = set_and_verify(fd, device, *exposure, static_cast<std::int32_t>(wanted),
                                      "exposure", report)) {
        return Report::failure(*error);
      }
    }
    if (const auto now = read_control(fd, V4L2_CID_EXPOSURE_ABSOLUTE)) {
      report.exposure_us = 100.0 * *now;
    }
  } else if (request.exposure_us) {
    return Report::failure(device +
                           ": exposure requested but the driver has no absolute exposure control "
                           "(V4L2_CID_EXPOSURE_ABSOLUTE)");
  } else {
    report.warnings.push_back(device + ": no absolute exposure control; exposure time unknown");
  }

  // Gain in driver units.
  auto gain = find_control(fd, V4L2_CID_GAIN);
  if (!gain) gain = find_control(fd, V4L2_CID_ANALOGUE_GAIN);
  if (gain) {
    if (request.gain) {
      const std::string shown = std::to_string(*request.gain);
      if (auto error = check_range(device, *gain, *request.gain, "gain", shown)) {
        return Report::failure(*error);
      }
      if (auto error = set_and_verify(fd, device, *gain, *request.gain, "gain", report)) {
        return Report::failure(*error);
      }
    }
    report.gain = read_control(fd, gain->query.id);
  } else if (request.gain) {
    return Report::failure(device + ": gain requested but the driver has no gain control");
  } else {
    report.warnings.push_back(device + ": no gain control; gain unknown");
  }
  return Report::success(std::move(report));
}

std::vector<std::string> v4l2_control_features(int fd) {
  struct Feature {
    std::uint32_t id;
    const char* word;
  };
  const Feature features[] = {
      {V4L2_CID_EXPOSURE_ABSOLUTE, "exposure"},
      {V4L2_CID_GAIN, "gain"},
      {V4L2_CID_ANALOGUE_GAIN, "analogue gain"},
      {V4L2_CID_GAMMA, "gamma"},
      {V4L2_CID_EXPOSURE_AUTO, "auto exposure"},
      {V4L2_CID_AUTOGAIN, "auto gain"},
      {V4L2_CID_AUTO_WHITE_BALANCE, "auto white balance"},
  };
  std::vector<std::string> words;
  for (const Feature& feature : features) {
    if (find_control(fd, feature.id)) words.emplace_back(feature.word);
  }
  return words;
}

}  // namespace flutterscan::capture
