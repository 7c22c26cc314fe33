// `flutterscan device set-code CODE [--id N] [--any-mask] [--select] [--save]`: upload a
// code, optionally select it and store everything in flash.

#include <cstdio>
#include <memory>
#include <string>

#include "app/code_arguments.hpp"
#include "app/device_commands.hpp"
#include "app/device_target.hpp"

namespace flutterscan::app {
namespace {

struct SetCodeOptions {
  DeviceTarget target;
  std::string code;
  int id = 0;
  bool any_mask = false;
  bool select = false;
  bool save = false;
};

void run(const SetCodeOptions& options) {
  // The code is checked before anything is opened.
  const LedCode code = parse_code_argument(options.code, 0, !options.any_mask);
  DeviceSession session(options.target);
  const auto info = session.client().info();
  if (code.leds() > info.led_count)
    throw UsageError("code '" + options.code + "' uses " + std::to_string(code.leds()) +
                     " LEDs but the controller has " + std::to_string(info.led_count));
  if (options.id >= info.max_codes)
    throw UsageError("--id " + std::to_string(options.id) + ": the controller has code ids 0.." +
                     std::to_string(info.max_codes - 1));
  const auto reply = value_or_throw(
      session.client().set_code(static_cast<std::uint8_t>(options.id), code, !options.any_mask));
  std::printf("code %d stored: %u slots, %d LEDs%s\n", options.id, reply.slots_received,
              code.leds(), options.any_mask ? "" : ", one LED per slot");
  if (options.select) {
    value_or_throw(session.client().select_code(static_cast<std::uint8_t>(options.id)));
    std::printf("code %d selected\n", options.id);
  }
  if (options.save) {
    const auto saved = value_or_throw(session.client().save_config());
    std::printf("saved %u bytes (CRC-32 %08X)\n", saved.bytes_written, saved.crc32);
  }
}

}  // namespace

void add_device_set_code(CLI::App& device) {
  auto options = std::make_shared<SetCodeOptions>();
  CLI::App* command =
      device.add_subcommand("set-code", "Upload a code (digits or a library name) to a code slot");
  command->add_option("CODE", options->code, "code digits (slot masks) or a library code name")
      ->required();
  command->add_option("--id", options->id, "code slot")->check(CLI::Range(0, 7));
  command->add_flag("--any-mask", options->any_mask,
                    "allow slots with several or no LEDs (default: exactly one LED per slot)");
  command->add_flag("--select", options->select, "select it too (SelectCode)");
  command->add_flag("--save", options->save, "then store codes and settings in flash (SaveConfig)");
  add_device_target_options(*command, options->target);
  command->callback([options] { run(*options); });
}

}  // namespace flutterscan::app
