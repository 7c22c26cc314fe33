// `flutterscan devices`: every controller on USB, in application or DFU mode,
// with serial numbers and firmware versions, and which ones run firmware older
// than the one installed with this flutterscan.

#include <cstdio>
#include <memory>
#include <string>
#include <tuple>

#include "app/commands.hpp"
#include "app/device_target.hpp"
#include "app/installed_firmware.hpp"
#include "device/usb_discovery.hpp"

namespace flutterscan::app {
namespace {

void run() {
  const auto found = device::find_controllers();
  if (!found.ok()) throw_device_error(found.error());
  const auto bundled = installed_firmware();
  if (found.value().empty()) {
    std::printf("no flutterscan controller is connected\n");
    return;
  }
  std::printf("%-24s  %-14s  %-8s  %s\n", "serial", "mode", "firmware", "notes");
  for (const auto& entry : found.value()) {
    std::string version = "-";
    std::string notes = entry.problem;
    if (entry.mode == device::DeviceMode::kApplication && !entry.serial.empty()) {
      device::ClientOptions options;
      options.reply_timeout = std::chrono::milliseconds(300);
      options.retries = 1;
      options.reconnect = false;
      const auto client =
          device::ControllerClient::connect(device::hid_opener(entry.serial), options);
      if (client.ok()) {
        const auto info = client.value()->info();
        version = version_text(info.firmware_major, info.firmware_minor, info.firmware_patch);
        if (bundled && std::tie(info.firmware_major, info.firmware_minor, info.firmware_patch) <
                           std::tie(bundled->header.version_major, bundled->header.version_minor,
                                    bundled->header.version_patch))
          notes = "older than the firmware installed with this flutterscan (" +
                  version_text(bundled->header.version_major, bundled->header.version_minor,
                               bundled->header.version_patch) +
                  "): run flutterscan flash --device " + entry.serial;
      } else {
        notes = client.error().message;
      }
    } else if (entry.mode == device::DeviceMode::kBootloader) {
      notes = notes.empty() ? "waiting for an image: run flutterscan flash" : notes;
    }
    std::printf("%-24s  %-14s  %-8s  %s\n",
                entry.serial.empty() ? "(unknown)" : entry.serial.c_str(),
                device::mode_name(entry.mode), version.c_str(), notes.c_str());
  }
}

}  // namespace

void add_devices(CLI::App& app) {
  CLI::App* command = app.add_subcommand(
      "devices", "LED controllers on USB (application and DFU mode), serials and versions");
  command->callback([] { run(); });
}

}  // namespace flutterscan::app
