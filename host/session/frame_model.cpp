#include "session/frame_model.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "imaging/capture_descriptor.hpp"
#include "imaging/limits.hpp"
#include "imaging/motion_frame.hpp"

namespace flutterscan::session {

double belt_speed_px_per_us(const ExposureRecord& event, const OpticsConfig& optics) {
  const double duration_us = static_cast<double>(event.slot_count) * event.slot_time_us;
  if (duration_us <= 0) return 0;
  if (!optics.encoder) return optics.nominal_blur_px / duration_us;
  return std::abs(static_cast<double>(event.encoder_delta)) * optics.px_per_count / duration_us;
}

std::string blur_out_of_range(const ExposureRecord& event, const OpticsConfig& optics,
                              const capture::FrameFormat& format) {
  imaging::Direction direction = imaging::Direction::kPlusX;
  imaging::parse_direction(optics.direction, direction);
  const int along = imaging::length_along_motion(direction, format.width, format.height);
  const double longest = std::min(static_cast<double>(along) - 1, imaging::kMaxBlurPx);
  const double blur = optics.encoder
                          ? std::abs(static_cast<double>(event.encoder_delta)) * optics.px_per_count
                          : optics.nominal_blur_px;
  if (std::isfinite(blur) && blur >= 0 && blur <= longest) return {};
  std::ostringstream text;
  text.precision(15);
  text << "exposure " << event.frame_counter << ": blur-out-of-range: ";
  if (optics.encoder)
    text << "encoder counts " << event.encoder_delta << " x optics.px_per_count "
         << optics.px_per_count << " = ";
  else
    text << "optics.nominal_blur_px = ";
  text << blur << " px is outside [0, " << longest << "] px (the frame is " << along
       << " px along the motion" << (longest < along - 1 ? ", and a blur is at most " : "");
  if (longest < along - 1) text << imaging::kMaxBlurPx << " px";
  text << ")";
  return text.str();
}

Result<imaging::CaptureModel, std::string> frame_model(const ExposureRecord& event,
                                                       const LedCode& code,
                                                       const SessionConfig& config,
                                                       const capture::FrameFormat& format) {
  using Out = Result<imaging::CaptureModel, std::string>;
  const std::string where = "exposure " + std::to_string(event.frame_counter);
  if (event.slot_count != code.length())
    return Out::failure(where + ": " + std::to_string(event.slot_count) +
                        " slots, the session's code has " + std::to_string(code.length()));
  const OpticsConfig& o = config.optics;
  imaging::CaptureModel m;
  m.code = code;
  m.blur_px = o.encoder ? std::abs(static_cast<double>(event.encoder_delta)) * o.px_per_count
                        : o.nominal_blur_px;
  imaging::parse_direction(o.direction, m.direction);
  if (event.encoder_delta < 0) {
    switch (m.direction) {
      case imaging::Direction::kPlusX:
        m.direction = imaging::Direction::kMinusX;
        break;
      case imaging::Direction::kMinusX:
        m.direction = imaging::Direction::kPlusX;
        break;
      case imaging::Direction::kPlusY:
        m.direction = imaging::Direction::kMinusY;
        break;
      case imaging::Direction::kMinusY:
        m.direction = imaging::Direction::kPlusY;
        break;
    }
  }
  const bool mono = format.pixel_format == capture::PixelFormat::kMono8 ||
                    format.pixel_format == capture::PixelFormat::kMono16;
  m.channels = mono ? 1 : 3;
  m.leds = 3;
  m.crosstalk = mono ? std::vector<double>{1, 1, 1} : o.crosstalk;
  const auto per_bit = imaging::budgeted_led_electrons(code, o.electrons, o.cap);
  m.led_electrons.assign(per_bit.begin(), per_bit.begin() + 3);
  m.ambient_electrons.assign(static_cast<std::size_t>(m.channels), 0.0);
  m.read_noise = o.read_noise_e;
  m.full_well = o.full_well_e;
  m.bit_depth = format.bit_depth;
  m.black_level = o.black_level_dn;
  m.gain = o.gain_e_per_dn > 0 ? o.gain_e_per_dn : o.full_well_e / (std::pow(2.0, m.bit_depth) - 1);
  m.bayer_rggb = capture::is_bayer_mosaic(format.pixel_format);
  if (auto problem = imaging::capture_model_problem(m); !problem.empty())
    return Out::failure(where + ": " + problem);
  return Out::success(std::move(m));
}

}  // namespace flutterscan::session
