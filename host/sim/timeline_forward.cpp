#include "sim/timeline_forward.hpp"

#include <algorithm>
#include <cmath>

#include "imaging/motion_frame.hpp"

namespace flutterscan::sim {
namespace {

using imaging::Plane;

/// out[n] = sum_j taps[j] in[n - j], `in` clamped at its left edge (the belt
/// continues upstream); the same loop as the plain forward model.
void blur_row(std::span<const float> in, std::span<float> out, const std::vector<double>& taps) {
  const int width = static_cast<int>(in.size());
  for (int n = 0; n < width; ++n) {
    double sum = 0;
    for (std::size_t j = 0; j < taps.size(); ++j) {
      const int source = std::max(0, n - static_cast<int>(j));
      sum += taps[j] * in[static_cast<std::size_t>(source)];
    }
    out[static_cast<std::size_t>(n)] = static_cast<float>(sum);
  }
}

/// Adds taps * in to out (double accumulation per row, stored as float).
void blur_row_add(std::span<const float> in, std::span<float> out,
                  const std::vector<double>& taps) {
  std::vector<float> part(in.size());
  blur_row(in, part, taps);
  for (std::size_t i = 0; i < part.size(); ++i) out[i] += part[i];
}

}  // namespace

imaging::Image expected_electrons_timeline(const Plane& reflectance,
                                           const imaging::CaptureModel& model,
                                           std::span<const imaging::ExposureSegment> segments) {
  const Plane moving = imaging::to_motion_frame(reflectance, model.direction);
  imaging::Image out;
  for (int c = 0; c < model.channels; ++c) {
    const auto taps = imaging::timeline_channel_psf(model, c, segments);
    Plane blurred(moving.width, moving.height);
    for (int y = 0; y < moving.height; ++y) blur_row(moving.row(y), blurred.row(y), taps);
    out.channels.push_back(imaging::from_motion_frame(blurred, model.direction));
  }
  return out;
}

double rolling_shutter_phase(int row, double line_time, double slot_time, int slots) {
  double phase = std::fmod(row * line_time / slot_time, static_cast<double>(slots));
  if (phase < 0) phase += slots;
  return phase;
}

Result<imaging::Image, std::string> expected_rolling_shutter_electrons(
    const Plane& reflectance, const imaging::CaptureModel& model, double line_time,
    double slot_time) {
  using Out = Result<imaging::Image, std::string>;
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
  for (int y = 0; y < moving.height; ++y) {
    const auto segments = imaging::cyclic_phase_segments(
        model, rolling_shutter_phase(y, line_time, slot_time, model.code.length()));
    for (int c = 0; c < model.channels; ++c)
      blur_row(moving.row(y), out.channels[static_cast<std::size_t>(c)].row(y),
               imaging::timeline_channel_psf(model, c, segments));
  }
  for (auto& plane : out.channels) plane = imaging::from_motion_frame(plane, model.direction);
  return Out::success(std::move(out));
}

Result<imaging::Image, std::string> expected_colour_electrons(std::span<const Plane> bands,
                                                              const imaging::CaptureModel& model) {
  using Out = Result<imaging::Image, std::string>;
  if (model.channels != 3 || model.leds != 3)
    return Out::failure("colour scene: the capture model needs 3 channels and 3 LEDs");
  if (bands.size() != 3) return Out::failure("colour scene: one reflectance plane per LED (3)");
  for (const auto& b : bands)
    if (b.width != bands[0].width || b.height != bands[0].height || b.empty())
      return Out::failure("colour scene: the band planes must be non-empty and of equal size");
  const auto segments = imaging::uniform_segments(model);
  std::vector<Plane> moving;
  for (const auto& b : bands) moving.push_back(imaging::to_motion_frame(b, model.direction));
  std::vector<std::vector<double>> led_taps;
  for (int k = 0; k < 3; ++k) led_taps.push_back(imaging::timeline_led_psf(model, k, segments));
  imaging::Image out;
  for (int c = 0; c < 3; ++c) {
    Plane sum(moving[0].width, moving[0].height);
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
      for (int y = 0; y < sum.height; ++y)
        blur_row_add(moving[static_cast<std::size_t>(k)].row(y), sum.row(y), taps);
    }
    out.channels.push_back(imaging::from_motion_frame(sum, model.direction));
  }
  return Out::success(std::move(out));
}

}  // namespace flutterscan::sim
