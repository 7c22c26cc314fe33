#pragma once
// What the `device` and `flash` commands share: the --device option (a serial
// number, or `sim` for the in-process virtual controller), opening a client to
// the chosen controller, and turning device errors into CLI errors (exit 2 for
// bad input or an ambiguous choice, exit 1 for the rest).

#include <CLI/CLI.hpp>

#include <atomic>
#include <memory>
#include <string>
#include <thread>

#include "app/cli_errors.hpp"
#include "device/controller_client.hpp"
#include "device/device_error.hpp"
#include "device/virtual_controller.hpp"

namespace flutterscan::app {

/// \brief --device and link options of a device command.
struct DeviceTarget {
  std::string device;  ///< serial number, "sim", or empty (the only controller)
  int timeout_ms = 500;
  int retries = 2;
};

/// \brief The --device value that selects the virtual controller.
inline constexpr const char* kSimDevice = "sim";

/// \brief Adds --device, --timeout-ms and --retries.
void add_device_target_options(CLI::App& command, DeviceTarget& target);

/// \brief Runs the virtual controller's clock in real time and, when asked,
/// strobes it like a camera (for `--device sim`).
class SimDriver {
 public:
  explicit SimDriver(std::shared_ptr<device::VirtualController> controller);
  ~SimDriver();
  SimDriver(const SimDriver&) = delete;
  SimDriver& operator=(const SimDriver&) = delete;
  /// \brief Camera exposures of `exposure_us` at `rate_hz` (0: no camera).
  void set_camera(double rate_hz, std::uint32_t exposure_us);

 private:
  void run();
  std::shared_ptr<device::VirtualController> controller_;
  std::atomic<bool> stop_{false};
  std::atomic<double> rate_hz_{0};
  std::atomic<std::uint32_t> exposure_us_{10'000};
  std::thread thread_;
};

/// \brief An open controller: the client, and for `sim` the virtual controller
/// (its flash page is kept in a state file between runs).
class DeviceSession {
 public:
  /// \brief Opens the controller `target` names; throws UsageError or RuntimeFailure.
  explicit DeviceSession(const DeviceTarget& target);
  ~DeviceSession();
  DeviceSession(const DeviceSession&) = delete;
  DeviceSession& operator=(const DeviceSession&) = delete;

  device::ControllerClient& client() { return *client_; }
  /// \brief The virtual controller's driver, or nullptr for a USB controller.
  SimDriver* sim() { return driver_.get(); }

 private:
  std::shared_ptr<device::VirtualController> virtual_controller_;
  std::unique_ptr<SimDriver> driver_;
  std::unique_ptr<device::ControllerClient> client_;
  std::string sim_state_path_;
};

/// \brief Where `--device sim` keeps its flash page: $FLUTTERSCAN_SIM_STATE, else
/// $XDG_RUNTIME_DIR/flutterscan-sim.flash, else /tmp/flutterscan-sim-UID.flash.
std::string sim_state_path();

/// \brief Throws the CLI error for `error`: UsageError (exit 2) for bad input,
/// an ambiguous controller choice or an argument the controller refused as out
/// of range; RuntimeFailure (exit 1) otherwise.
[[noreturn]] void throw_device_error(const device::DeviceError& error);

/// \brief The value, or throw_device_error.
template <typename T>
T value_or_throw(const device::Expected<T>& result) {
  if (!result.ok()) throw_device_error(result.error());
  return result.value();
}

/// \brief "1.2.3".
std::string version_text(std::uint8_t major, std::uint8_t minor, std::uint8_t patch);

}  // namespace flutterscan::app
