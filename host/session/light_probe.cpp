#include "session/light_probe.hpp"

#include <cmath>
#include <sstream>
#include <vector>

#include "codes/scheme_choice.hpp"
#include "session/frame_model.hpp"
#include "session/read_record.hpp"

namespace flutterscan::session {
namespace {

std::string digits_of(const LedCode& code) {
  std::string text(static_cast<std::size_t>(code.length()), '0');
  text.resize(code.format(text));
  return text;
}

}  // namespace

LedCode light_probe_pattern(int slots) {
  return LedCode::from_masks(std::vector<std::uint8_t>(static_cast<std::size_t>(slots), 7), 3)
      .value();
}

Captured<imaging::LightLevel> measure_light_level(
    const SessionConfig& config, std::shared_ptr<device::VirtualController> virtual_controller,
    const std::function<void(const std::string&)>& progress) {
  using Out = Captured<imaging::LightLevel>;
  RigOptions options;
  options.config = config;
  options.virtual_controller = std::move(virtual_controller);
  options.progress = progress;
  auto rig = CalibrationRig::open(std::move(options));
  if (!rig.ok()) return Out::failure(rig.error());
  const LedCode probe = light_probe_pattern();
  auto frames = rig.value()->lit(probe, config.controller.probe_frames,
                                 "light probe (every LED in every slot)");
  if (!frames.ok()) return Out::failure(frames.error());
  // The probe's model at E = 1: the session's optics and the camera's format.
  ExposureRecord event;
  event.slot_count = static_cast<std::uint16_t>(probe.length());
  event.slot_time_us = config.controller.slot_time_us;
  event.code_id = kCalibrationCodeId;
  auto model = frame_model(event, probe, config, rig.value()->format());
  if (!model.ok())
    return Out::failure({rig.value()->where() + ", light probe: " + model.error(), true});
  imaging::LightLevelOptions level_options;
  level_options.paper_reflectance = config.optics.paper_reflectance;
  auto level = imaging::estimate_light_level(
      frames.value(), imaging::unit_light_model(model.value(), probe, config.optics.cap),
      level_options);
  if (!level.ok())
    return Out::failure({rig.value()->where() + ", light probe: " + level.error(), false});
  return Out::success(level.value());
}

Captured<SchemeLight> choose_scheme_from_light(
    SessionConfig& config, std::shared_ptr<device::VirtualController> virtual_controller,
    const std::function<void(const std::string&)>& progress) {
  using Out = Captured<SchemeLight>;
  SchemeLight light;
  light.paper_reflectance = config.optics.paper_reflectance;
  light.probe = digits_of(light_probe_pattern());
  if (config.optics.electrons_given) light.configured = config.optics.electrons;
  auto measured = measure_light_level(config, std::move(virtual_controller), progress);
  if (measured.ok()) {
    light.level = measured.value();
    light.electrons = measured.value().electrons;
  } else if (light.configured) {
    light.not_measured = measured.error().message;
    light.electrons = *light.configured;
  } else {
    return Out::failure({"scheme auto: the light level could not be measured (" +
                             measured.error().message +
                             "), and the config gives no optics.electrons to fall back to",
                         measured.error().bad_input});
  }
  config.controller.scheme =
      codes::choose_scheme(light.electrons, config.optics.read_noise_e, config.optics.cap);
  config.controller.parsed_code = config.controller.scheme->code;
  if (!light.configured) config.optics.electrons = light.electrons;
  return Out::success(light);
}

nlohmann::json scheme_light_json(const SchemeLight& light) {
  nlohmann::json j = {{"electrons", rounded(light.electrons, 1)},
                      {"source", light.level ? "measured" : "configured"},
                      {"paper_reflectance", light.paper_reflectance},
                      {"probe", light.probe}};
  if (light.configured) j["configured_electrons"] = *light.configured;
  if (light.level) {
    const imaging::LightLevel& l = *light.level;
    j["measured_electrons"] = rounded(l.electrons, 1);
    j["frames"] = l.frames;
    j["pixels"] = l.pixels;
    j["paper_electrons"] = rounded(l.paper_electrons, 1);
    j["background_electrons"] = rounded(l.background_electrons, 1);
    j["saturated_share"] = l.saturated_share;
  }
  if (!light.not_measured.empty()) j["not_measured"] = light.not_measured;
  return j;
}

std::string describe_scheme_light(const SchemeLight& light) {
  std::ostringstream text;
  text.precision(4);
  if (light.level) {
    const imaging::LightLevel& l = *light.level;
    text << "light measured " << l.electrons << " e- per channel (brightest paper, reflectance "
         << light.paper_reflectance << ", " << l.pixels << " pixels of " << l.frames
         << " probe frames";
    if (light.configured) text << "; optics.electrons says " << *light.configured;
    text << ")";
  } else {
    text << "the configured light optics.electrons = " << light.electrons
         << " e- per channel (not measured: " << light.not_measured << ")";
  }
  return text.str();
}

}  // namespace flutterscan::session
