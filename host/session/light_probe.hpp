#pragma once
// `controller.code = "auto"` (`scan --scheme auto`): before the pipeline
// starts, the session measures the light level E on the line and picks the
// capture scheme the regime map says wins there (codes/scheme_choice.hpp).
//
// The measurement: the session's camera and controller, opened as the live
// calibrations open them (calibration_capture.hpp), light the moving belt with
// the probe pattern, every LED in every slot (rect-white: each LED then emits
// its whole budget E whatever the cap), for controller.probe_frames frames
// uploaded as code 7; E comes from the brightest paper in those frames
// (imaging/light_level.hpp), taken to have reflectance
// optics.paper_reflectance (1 unless configured). The probe leaves the
// controller disarmed; the session then sets it up with the chosen code as
// code 0 as usual.
//
// When the frames cannot give a level (no frames or events, no bright paper,
// paper saturated or lost in noise), a config that gives optics.electrons
// falls back to it and says so; without it the session fails naming why.

#include <functional>
#include <memory>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "imaging/light_level.hpp"
#include "session/calibration_capture.hpp"
#include "session/session_config.hpp"

namespace flutterscan::device {
class VirtualController;
}

namespace flutterscan::session {

/// \brief The light level an auto scheme was chosen at, and where it came from.
struct SchemeLight {
  double electrons = 0;                      ///< E the scheme was chosen at
  std::optional<imaging::LightLevel> level;  ///< the measurement, when it worked
  std::optional<double> configured;          ///< optics.electrons, when the config gave it
  std::string not_measured;                  ///< why the measurement failed (empty if it worked)
  double paper_reflectance = 1;              ///< the brightest paper taken as this
  std::string probe;                         ///< the probe pattern's digits
};

/// \brief The probe pattern: all three LEDs in each of `slots` slots.
LedCode light_probe_pattern(int slots = 52);

/// \brief Lights the belt with the probe through the camera and controller of
/// `config` and measures E. The failure says what (the line, or the frames).
Captured<imaging::LightLevel> measure_light_level(
    const SessionConfig& config, std::shared_ptr<device::VirtualController> virtual_controller,
    const std::function<void(const std::string&)>& progress);

/// \brief For code "auto": measures the light (measure_light_level), falls back
/// to a configured optics.electrons when that fails, and sets config's scheme
/// and code 0 to the regime map's choice there. Without a configured light the
/// frame model's optics.electrons becomes the measured one. Fails when
/// neither the frames nor the config give a level.
Captured<SchemeLight> choose_scheme_from_light(
    SessionConfig& config, std::shared_ptr<device::VirtualController> virtual_controller,
    const std::function<void(const std::string&)>& progress);

/// \brief summary.json's scheme_choice.light.
nlohmann::json scheme_light_json(const SchemeLight& light);

/// \brief One line for the start-up message: the light and where it came from.
std::string describe_scheme_light(const SchemeLight& light);

}  // namespace flutterscan::session
