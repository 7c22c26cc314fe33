#pragma once
// Before the pipeline runs (docs/session.md): the configuration checked, the
// flat field loaded, and for controller.code = "auto" the light measured on
// the line and the scheme chosen from it (light_probe.hpp). Everything refused
// here is the user's input (exit 2) unless said otherwise.

#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "flutterscan/common/result.hpp"
#include "imaging/flat_field.hpp"
#include "session/calibration_capture.hpp"
#include "session/light_probe.hpp"
#include "session/results_server.hpp"
#include "session/session_config.hpp"

namespace flutterscan::device {
class VirtualController;
}

namespace flutterscan::session {

/// \brief The flat field of optics.flat_field (calibrate flat), none when not
/// configured; the error names the file and why it was refused.
Result<std::optional<imaging::FlatField>, std::string> load_flat_field(const OpticsConfig& optics);

/// \brief What the sim camera needs of the controller (spec "sim", sync
/// "slave"); the problem, empty when none.
std::string check_sim_line(const SessionConfig& config);

/// \brief The session's inputs checked in turn: the configuration
/// (check_config, "config: ..."), the flat field (loaded), the sim line.
/// The flat field, or the first problem.
Result<std::optional<imaging::FlatField>, std::string> check_session_inputs(SessionConfig& config);

/// \brief Scheme auto: measures the light on the line and chooses the scheme
/// (choose_scheme_from_light), telling `say` the choice, and warning when the
/// brightest paper was barely brighter than the rest.
Captured<SchemeLight> choose_scheme(SessionConfig& config,
                                    std::shared_ptr<device::VirtualController> virtual_controller,
                                    const std::function<void(const std::string&)>& say);

/// \brief The session folder: output.dir, or a new timestamped folder under it.
std::string session_folder_name(const OutputConfig& output);

/// \brief Opens the result outputs of `config` on `server`: the TCP port
/// (told to `listening`, which may be empty) and the serial line; the error
/// names the one that failed.
std::string open_result_outputs(const ResultsConfig& config, ResultsServer& server,
                                const std::function<void(int port)>& listening);

}  // namespace flutterscan::session
