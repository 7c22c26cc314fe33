// `flutterscan cameras`: every camera backend compiled in and the cameras
// each finds attached, with their pixel formats and features.

#include <iostream>

#include "app/commands.hpp"
#include "capture/camera_source.hpp"

namespace flutterscan::app {

void add_cameras(CLI::App& app) {
  CLI::App* command = app.add_subcommand("cameras", "List camera backends and attached cameras");
  command->callback([] {
    for (const auto& backend : capture::camera_backends()) {
      std::cout << backend.scheme << ": " << backend.summary << "\n";
      const auto found = backend.list ? backend.list() : std::vector<capture::CameraInfo>{};
      if (found.empty()) std::cout << "  (none attached)\n";
      for (const auto& camera : found) {
        std::cout << "  " << camera.spec << "  " << camera.description << "\n";
        if (!camera.pixel_formats.empty()) {
          std::cout << "    formats:";
          for (const auto& f : camera.pixel_formats) std::cout << " " << f;
          std::cout << "\n";
        }
        if (!camera.features.empty()) {
          std::cout << "    features:";
          for (const auto& f : camera.features) std::cout << " " << f << ";";
          std::cout << "\n";
        }
      }
    }
  });
}

}  // namespace flutterscan::app
