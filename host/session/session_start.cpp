#include "session/session_start.hpp"

#include <nlohmann/json.hpp>

#include <ctime>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <utility>

namespace flutterscan::session {

std::string check_sim_line(const SessionConfig& config) {
  const bool sim_camera = config.camera.spec == "sim" || config.camera.spec.rfind("sim:", 0) == 0;
  if (sim_camera && config.controller.spec != "sim")
    return "camera 'sim' needs the virtual controller: set controller.spec = \"sim\"";
  if (sim_camera && config.controller.sync != "slave")
    return "camera 'sim' strobes the controller: controller.sync must be \"slave\"";
  return "";
}

Result<std::optional<imaging::FlatField>, std::string> load_flat_field(const OpticsConfig& optics) {
  using Out = Result<std::optional<imaging::FlatField>, std::string>;
  if (optics.flat_field.empty()) return Out::success(std::nullopt);
  std::ifstream in(optics.flat_field);
  const auto json = nlohmann::json::parse(in, nullptr, false);
  auto parsed = json.is_discarded()
                    ? Result<imaging::FlatField, std::string>::failure("not readable JSON")
                    : imaging::flat_field_from_json(json);
  if (!parsed.ok())
    return Out::failure("config: optics.flat_field '" + optics.flat_field + "': " + parsed.error());
  return Out::success(std::move(parsed.value()));
}

Result<std::optional<imaging::FlatField>, std::string> check_session_inputs(SessionConfig& config) {
  using Out = Result<std::optional<imaging::FlatField>, std::string>;
  if (auto problem = check_config(config); !problem.empty())
    return Out::failure("config: " + problem);
  auto flat = load_flat_field(config.optics);
  if (!flat.ok()) return flat;
  if (auto problem = check_sim_line(config); !problem.empty()) return Out::failure(problem);
  return flat;
}

Captured<SchemeLight> choose_scheme(SessionConfig& config,
                                    std::shared_ptr<device::VirtualController> virtual_controller,
                                    const std::function<void(const std::string&)>& say) {
  auto light = choose_scheme_from_light(config, std::move(virtual_controller),
                                        [&](const std::string& m) { say("light probe: " + m); });
  if (!light.ok()) return light;
  const SchemeLight& scheme_light = light.value();
  const codes::SchemeChoice& scheme = *config.controller.scheme;
  std::ostringstream text;
  text << "scheme auto: " << scheme.scheme << " at " << describe_scheme_light(scheme_light)
       << "; regime map cell " << scheme.cell_electrons << " e-, read noise "
       << scheme.cell_read_noise << " e-, cap " << scheme.cell_cap << ": best coded scheme "
       << (scheme.margin_db >= 0 ? "+" : "") << scheme.margin_db
       << " dB against the best white strobe";
  say(text.str());
  if (const auto& l = scheme_light.level; l && l->paper_electrons < 1.25 * l->background_electrons)
    say("warning: scheme auto: the brightest paper is barely brighter than the rest of the "
        "probe frames: if no label was in view, the belt was taken for paper and the light "
        "is underestimated");
  return light;
}

std::string session_folder_name(const OutputConfig& output) {
  namespace fs = std::filesystem;
  if (!output.timestamped_subfolder) return output.dir;
  const std::time_t t = std::time(nullptr);
  std::tm local{};
  localtime_r(&t, &local);
  char stamp[32];
  std::strftime(stamp, sizeof stamp, "%Y%m%d-%H%M%S", &local);
  std::string base = (fs::path(output.dir) / stamp).string();
  std::string name = base;
  for (int n = 2; fs::exists(name); ++n) name = base + "-" + std::to_string(n);
  return name;
}

std::string open_result_outputs(const ResultsConfig& config, ResultsServer& server,
                                const std::function<void(int port)>& listening) {
  if (config.tcp_port >= 0) {
    if (auto p = server.listen(config.tcp_bind, config.tcp_port); !p.empty()) return p;
    if (listening) listening(server.port());
  }
  if (!config.serial.empty())
    if (auto p = server.open_serial(config.serial, config.serial_baud); !p.empty()) return p;
  return "";
}

}  // namespace flutterscan::session
