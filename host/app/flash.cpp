// `flutterscan flash [FILE] [--device SERIAL]`: update a controller's firmware
// over USB DFU; without FILE, the firmware installed with this flutterscan.
// The image is checked (header, board, CRC) before any device is touched.

#include <cstdio>
#include <iostream>
#include <memory>
#include <string>

#include "app/commands.hpp"
#include "app/device_target.hpp"
#include "app/installed_firmware.hpp"
#include "device/dfu_flasher.hpp"

namespace flutterscan::app {
namespace {

struct FlashCliOptions {
  std::string file;
  std::string device;
  int wait_s = 10;
};

/// A progress bar on stderr, redrawn in place.
void draw_progress(std::size_t done, std::size_t total) {
  constexpr int kWidth = 40;
  const double share = total == 0 ? 1.0 : static_cast<double>(done) / static_cast<double>(total);
  const int filled = static_cast<int>(share * kWidth);
  std::fprintf(stderr, "\r[%s%s] %3d%%  %zu/%zu KiB", std::string(filled, '#').c_str(),
               std::string(kWidth - filled, ' ').c_str(), static_cast<int>(share * 100),
               done / 1024, (total + 1023) / 1024);
  if (done >= total) std::fprintf(stderr, "\n");
  std::fflush(stderr);
}

void run(const FlashCliOptions& options) {
  if (options.device == kSimDevice)
    throw UsageError("flash: the virtual controller (--device sim) has no bootloader to flash");
  std::string path = options.file;
  if (path.empty()) {
    const auto installed = installed_firmware_path();
    if (!installed) {
      std::string tried;
      for (const auto& candidate : installed_firmware_candidates()) tried += "\n  " + candidate;
      throw UsageError(
          "flash: no FILE given and no firmware installed with this flutterscan; looked for:" +
          tried);
    }
    path = *installed;
  }
  // Checked before any device is touched.
  const auto image = value_or_throw(device::load_firmware_image(path, kStm32f405AppRegion));
  std::fprintf(stderr, "flutterscan: %s: firmware %u.%u.%u for board %u, %zu bytes, CRC-32 %08X\n",
               path.c_str(), image.header.version_major, image.header.version_minor,
               image.header.version_patch, image.header.board_id, image.bytes.size(),
               image.header.image_crc32);
  device::FlashOptions flash;
  if (!options.device.empty()) flash.serial = options.device;
  flash.enumerate_timeout = std::chrono::seconds(options.wait_s);
  flash.progress = draw_progress;
  flash.log = [](const std::string& line) { std::cerr << "flutterscan: " << line << "\n"; };
  const auto report = value_or_throw(device::flash_controller(image, flash));
  std::printf("controller %s now runs firmware %s (%.1f KiB/s download)\n", report.serial.c_str(),
              version_text(report.after.firmware_major, report.after.firmware_minor,
                           report.after.firmware_patch)
                  .c_str(),
              report.kib_per_second);
}

}  // namespace

void add_flash(CLI::App& app) {
  auto options = std::make_shared<FlashCliOptions>();
  CLI::App* command = app.add_subcommand(
      "flash", "Update a controller's firmware over USB DFU (.bin, .hex or .elf)");
  command->add_option("FILE", options->file,
                      "firmware image (default: the one installed with this flutterscan)");
  command->add_option("--device", options->device,
                      "serial number of the controller (default: the only one connected)");
  command
      ->add_option("--wait-s", options->wait_s,
                   "longest wait for the bootloader or the application to appear")
      ->check(CLI::Range(1, 120));
  command->callback([options] { run(*options); });
}

}  // namespace flutterscan::app
