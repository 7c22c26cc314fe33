#include "app/installed_firmware.hpp"

#include <filesystem>
#include <system_error>

namespace flutterscan::app {

namespace fs = std::filesystem;

std::vector<std::string> installed_firmware_candidates() {
  std::vector<std::string> out;
  std::error_code error;
  const fs::path exe = fs::read_symlink("/proc/self/exe", error);
  if (!error)
    out.push_back((exe.parent_path().parent_path() / FLUTTERSCAN_FIRMWARE_INSTALL_SUBDIR /
                   FLUTTERSCAN_FIRMWARE_FILE_NAME)
                      .string());
  out.push_back(FLUTTERSCAN_FIRMWARE_BUILD_PATH);
  return out;
}

std::optional<std::string> installed_firmware_path() {
  for (const auto& path : installed_firmware_candidates()) {
    std::error_code error;
    if (fs::is_regular_file(path, error)) return path;
  }
  return std::nullopt;
}

std::optional<device::FirmwareImage> installed_firmware() {
  const auto path = installed_firmware_path();
  if (!path) return std::nullopt;
  auto image = device::load_firmware_image(*path, kStm32f405AppRegion);
  if (!image.ok()) return std::nullopt;
  return image.value();
}

}  // namespace flutterscan::app
