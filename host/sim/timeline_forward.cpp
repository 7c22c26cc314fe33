#include "sim/timeline_forward.hpp"

#include <algorithm>
#include <cmath>

#include "imaging/motion_frame.hpp"
#include "sim/pixel_integration.hpp"

namespace flutterscan::sim {
namespace {

using imaging::Plane;

/// The segments on a grid `k` times finer.
std::vector<imaging::ExposureSegment> finer(std::span<const imaging::ExposureSegment> segments,
                                            int k) {
  std::vector<imaging::ExposureSegment> out(segments.begin(), segments.end());
  for (auto& s : out) {
    s.start_px *= k;
    s.width_px *= k;
  }
  return out;
}

}  // namespace

imaging::Image expected_electrons_timeline(const Plane& reflectance,
                                           const imaging::CaptureModel& given,
                                           std::span<const imaging::ExposureSegment> segments,
                                           int supersample) {
  const auto model = rendered_pixels(given);
  const Plane moving = imaging::to_motion_frame(reflectance, model.direction);
  const auto fine = finer(segments, supersample);
  imaging::Image out;
  for (int c = 0; c < model.channels; ++c)
    out.channels.push_back(imaging::from_motion_frame(
        blur_and_bin_rows(moving, imaging::timeline_channel_psf(model, c, fine), supersample),
        model.direction));
  return out;
}

double rolling_shutter_phase(int row, double line_time, double slot_time, int slots) {
  double phase = std::fmod(row * line_time / slot_time, static_cast<double>(slots));
  if (phase < 0) phase += slots;
  return phase;
}

Result<imaging::Image, std::string> expected_rolling_shutter_electrons(
    const Plane& reflectance, const imaging::CaptureModel& given, double line_time,
    double slot_time) {
  using Out = Result<imaging::Image, std::string>;
  const auto model = rendered_pixels(given);
  if (model.direction != imaging::Direction::kPlusX &&
      model.direction != imaging::Direction::kMinusX)
    return Out::failure(
        "rolling shutter: the motion must be along x (each image row one row of the motion)");
  if (!std::isfinite(line_time) || line_time < 0)
    return Out::failure("rolling shutter: the line time must be finite and >= 0");
  if (!std::isfinite(slot_time) || slot_time <= 0)
    return Out::failure("rolling shutter: the slot time must be finite and > 0");
  const Plane moving = imaging::to_motion_frame(reflectance, model.direction);
  imaging::Image out;
  for (int c = 0; c < model.channels; ++c) out.channels.emplace_back(moving.width, moving.height);
  Plane row(moving.width, 1);
  for (int y = 0; y < moving.height; ++y) {
    const auto segments = imaging::cyclic_phase_segments(
        model, rolling_shutter_phase(y, line_time, slot_time, model.code.length()));
    std::copy(moving.row(y).begin(), moving.row(y).end(), row.pixels.begin());
    for (int c = 0; c < model.channels; ++c) {
      const Plane blurred =
          blur_and_bin_rows(row, imaging::timeline_channel_psf(model, c, segments), 1);
      std::copy(blurred.pixels.begin(), blurred.pixels.end(),
                out.channels[static_cast<std::size_t>(c)].row(y).begin());
    }
  }
  for (auto& plane : out.channels) plane = imaging::from_motion_frame(plane, model.direction);
  return Out::success(std::move(out));
}

Result<imaging::Image, std::string> expected_colour_electrons(std::span<const Plane> bands,
                                                              const imaging::CaptureModel& model,
                                                              int supersample) {
  return expected_colour_electrons_timeline(bands, model, imaging::slot_segments(model),
                                            supersample);
}

Result<imaging::Image, std::string> expected_colour_electrons_timeline(
    std::span<const Plane> bands, const imaging::CaptureModel& given,
    std::span<const imaging::ExposureSegment> timeline, int supersample) {
  using Out = Result<imaging::Image, std::string>;
  const auto model = rendered_pixels(given);
  if (model.channels != 3 || model.leds != 3)
    return Out::failure("colour scene: the capture model needs 3 channels and 3 LEDs");
  if (bands.size() != 3) return Out::failure("colour scene: one reflectance plane per LED (3)");
  for (const auto& b : bands)
    if (b.width != bands[0].width || b.height != bands[0].height || b.empty())
      return Out::failure("colour scene: the band planes must be non-empty and of equal size");
  const auto segments = finer(timeline, supersample);
  std::vector<Plane> moving;
  for (const auto& b : bands) moving.push_back(imaging::to_motion_frame(b, model.direction));
  std::vector<std::vector<double>> led_taps;
  for (int k = 0; k < 3; ++k) led_taps.push_back(imaging::timeline_led_psf(model, k, segments));
  imaging::Image out;
  for (int c = 0; c < 3; ++c) {
    Plane sum(moving[0].width / supersample, moving[0].height / supersample);
    for (int k = 0; k < 3; ++k) {
      auto taps = led_taps[static_cast<std::size_t>(k)];
      const double mix = model.crosstalk[static_cast<std::size_t>(c * 3 + k)];
      for (double& t : taps) t *= mix;
      if (k == c) {  // the ambient light of channel c, over the whole exposure, on band c
        imaging::CaptureModel ambient_only = model;
        std::fill(ambient_only.led_electrons.begin(), ambient_only.led_electrons.end(), 0.0);
        const auto ambient = imaging::timeline_channel_psf(ambient_only, c, segments);
        if (ambient.size() > taps.size()) taps.resize(ambient.size(), 0.0);
        for (std::size_t j = 0; j < ambient.size(); ++j) taps[j] += ambient[j];
      }
      const Plane part = blur_and_bin_rows(moving[static_cast<std::size_t>(k)], taps, supersample);
      for (std::size_t i = 0; i < part.pixels.size(); ++i) sum.pixels[i] += part.pixels[i];
    }
    out.channels.push_back(imaging::from_motion_frame(sum, model.direction));
  }
  return Out::success(std::move(out));
}

}  // namespace flutterscan::sim
