#pragma once
// The line's LED controller and camera, opened the way a session opens them:
// the controller named by controller.spec ("sim", "auto" or a serial number)
// connected, disarmed and set up with the session's code (id 0), timing and
// sync mode; then the camera named by camera.spec made, opened and configured.
// Shared by run_session (session.cpp) and the live calibrations
// (calibration_capture.cpp).

#include <memory>
#include <string>

#include "capture/camera_source.hpp"
#include "device/controller_client.hpp"
#include "device/virtual_controller.hpp"
#include "session/frame_matcher.hpp"
#include "session/session.hpp"
#include "session/session_config.hpp"

namespace flutterscan::session {

/// \brief A connected controller (and the virtual one behind it for spec "sim").
struct ControllerLink {
  std::shared_ptr<device::VirtualController> virtual_controller;
  std::unique_ptr<device::ControllerClient> client;
  std::string description;  ///< "controller SERIAL" or "virtual controller (...)"
};

/// \brief Connects to the controller named by the config and sets it up for the
/// session: Disarm, SetCode 0 (the session's code), SelectCode 0, SetTiming,
/// SetMode. The error names the controller and the command refused; `bad_input`
/// is set when the spec names no controller (or several).
std::string connect_controller(const SessionConfig& config, const SessionHooks& hooks,
                               ControllerLink& link, bool& bad_input);

/// \brief The frame matcher's record of an exposure event from the controller.
ExposureRecord exposure_record(const device::EventNotice& notice);

/// \brief Makes, opens and configures the camera of `camera` (the sim one on
/// `controller`, which may be null for others). Null with `error` naming the
/// spec or the setting refused; `bad_input` for an unknown spec or a refused setting.
std::unique_ptr<capture::CameraSource> open_camera(const CameraConfig& camera,
                                                   device::VirtualController* controller,
                                                   std::string& error, bool& bad_input);

}  // namespace flutterscan::session
