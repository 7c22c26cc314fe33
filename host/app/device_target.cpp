#include "app/device_target.hpp"

#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <iterator>

#include "device/in_process_transport.hpp"
#include "device/usb_discovery.hpp"

namespace flutterscan::app {

using device::ErrorKind;

void add_device_target_options(CLI::App& command, DeviceTarget& target) {
  command.add_option("--device", target.device,
                     "serial number of the controller, or 'sim' for the built-in virtual "
                     "controller (default: the only one connected)");
  command.add_option("--timeout-ms", target.timeout_ms, "reply timeout per attempt")
      ->check(CLI::Range(1, 60'000));
  command.add_option("--retries", target.retries, "extra attempts after a timeout")
      ->check(CLI::Range(0, 10));
}

std::string version_text(std::uint8_t major, std::uint8_t minor, std::uint8_t patch) {
  return std::to_string(major) + "." + std::to_string(minor) + "." + std::to_string(patch);
}

[[noreturn]] void throw_device_error(const device::DeviceError& error) {
  switch (error.kind) {
    case ErrorKind::kBadInput:
    case ErrorKind::kAmbiguous:
      throw UsageError(error.message);
    case ErrorKind::kRejected:
      if (error.status == protocol::Status::kOutOfRange ||
          error.status == protocol::Status::kBadCode ||
          error.status == protocol::Status::kNoSuchCode ||
          error.status == protocol::Status::kAboveCeiling)
        throw UsageError(error.message);
      throw RuntimeFailure(error.message);
    default:
      throw RuntimeFailure(error.message);
  }
}

std::string sim_state_path() {
  if (const char* path = std::getenv("FLUTTERSCAN_SIM_STATE"); path != nullptr && *path != 0)
    return path;
  if (const char* dir = std::getenv("XDG_RUNTIME_DIR"); dir != nullptr && *dir != 0)
    return std::string(dir) + "/flutterscan-sim.flash";
  return "/tmp/flutterscan-sim-" + std::to_string(::getuid()) + ".flash";
}

// ---------------------------------------------------------------------------

SimDriver::SimDriver(std::shared_ptr<device::VirtualController> controller)
    : controller_(std::move(controller)), thread_([this] { run(); }) {}

SimDriver::~SimDriver() {
  stop_ = true;
  thread_.join();
}

void SimDriver::set_camera(double rate_hz, std::uint32_t exposure_us) {
  exposure_us_ = exposure_us;
  rate_hz_ = rate_hz;
}

void SimDriver::run() {
  using Clock = std::chrono::steady_clock;
  auto last = Clock::now();
  auto next_exposure = last;
  while (!stop_) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    const auto now = Clock::now();
    const auto elapsed = std::chrono::duration_cast<std::chrono::microseconds>(now - last);
    last = now;
    controller_->advance_us(static_cast<std::uint64_t>(elapsed.count()));
    const double rate = rate_hz_;
    if (rate > 0 && now >= next_exposure) {
      controller_->expose(exposure_us_);
      next_exposure = now + std::chrono::microseconds(static_cast<long>(1e6 / rate));
    }
  }
}

// ---------------------------------------------------------------------------

DeviceSession::DeviceSession(const DeviceTarget& target) {
  device::ClientOptions options;
  options.reply_timeout = std::chrono::milliseconds(target.timeout_ms);
  options.retries = target.retries;
  device::TransportOpener opener;
  if (target.device == kSimDevice) {
    device::VirtualControllerOptions sim;
    sim_state_path_ = sim_state_path();
    std::ifstream state(sim_state_path_, std::ios::binary);
    if (state)
      sim.initial_flash_page.assign(std::istreambuf_iterator<char>(state),
                                    std::istreambuf_iterator<char>());
    virtual_controller_ = std::make_shared<device::VirtualController>(sim);
    driver_ = std::make_unique<SimDriver>(virtual_controller_);
    opener = device::in_process_opener(virtual_controller_);
  } else {
    const auto found = device::find_controllers();
    if (!found.ok()) throw_device_error(found.error());
    std::optional<std::string> serial;
    if (!target.device.empty()) serial = target.device;
    const auto picked =
        device::pick_controller(found.value(), serial, device::DeviceMode::kApplication);
    if (!picked.ok()) {
      auto error = picked.error();
      // A controller waiting in its bootloader needs a flash, not a command.
      for (const auto& entry : found.value())
        if (entry.mode == device::DeviceMode::kBootloader && (!serial || entry.serial == *serial))
          error.message +=
              "\ncontroller " + entry.serial + " is in DFU bootloader mode: run flutterscan flash";
      throw_device_error(error);
    }
    opener = device::hid_opener(picked.value().serial);
  }
  auto client = device::ControllerClient::connect(opener, options);
  if (!client.ok()) throw_device_error(client.error());
  client_ = std::move(client.value());
  client_->set_notice_handler(
      [](const std::string& line) { std::cerr << "flutterscan: " << line << "\n"; });
}

DeviceSession::~DeviceSession() {
  client_.reset();
  driver_.reset();
  if (virtual_controller_) {
    // Keep the virtual controller's flash for the next run, written whole or not at all.
    const auto page = virtual_controller_->flash_page_contents();
    const std::string temporary = sim_state_path_ + ".tmp";
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(page.data()),
              static_cast<std::streamsize>(page.size()));
    out.close();
    if (out) std::rename(temporary.c_str(), sim_state_path_.c_str());
  }
}

}  // namespace flutterscan::app
