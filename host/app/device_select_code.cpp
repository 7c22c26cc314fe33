// `flutterscan device select-code N`: the code for the next Arm, or (armed) from
// the next exposure on.

#include <cstdio>
#include <memory>
#include <string>

#include "app/device_commands.hpp"
#include "app/device_target.hpp"

namespace flutterscan::app {
namespace {

struct SelectOptions {
  DeviceTarget target;
  int id = 0;
};

std::string id_text(std::uint8_t id) {
  return id == protocol::kNoCode ? "none" : std::to_string(id);
}

void run(const SelectOptions& options) {
  DeviceSession session(options.target);
  const auto reply =
      value_or_throw(session.client().select_code(static_cast<std::uint8_t>(options.id)));
  std::printf("active code %s, pending %s\n", id_text(reply.active_code_id).c_str(),
              id_text(reply.pending_code_id).c_str());
}

}  // namespace

void add_device_select_code(CLI::App& device) {
  auto options = std::make_shared<SelectOptions>();
  CLI::App* command = device.add_subcommand(
      "select-code", "Make a stored code the active one (armed: from the next exposure on)");
  command->add_option("N", options->id, "code slot")->required()->check(CLI::Range(0, 7));
  add_device_target_options(*command, options->target);
  command->callback([options] { run(*options); });
}

}  // namespace flutterscan::app
