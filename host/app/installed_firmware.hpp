#pragma once
// The controller firmware built with this flutterscan and installed beside it
// (share/flutterscan/firmware/ next to bin/), or in the build tree when run
// from there: what `flutterscan flash` flashes by default and what `devices`
// compares controllers with.

#include <optional>
#include <string>

#include "device/firmware_image.hpp"

namespace flutterscan::app {

/// \brief Paths tried for the product firmware, in order.
std::vector<std::string> installed_firmware_candidates();

/// \brief The first candidate that exists, if any.
std::optional<std::string> installed_firmware_path();

/// \brief The installed image loaded and checked, if there is a valid one.
std::optional<device::FirmwareImage> installed_firmware();

}  // namespace flutterscan::app
