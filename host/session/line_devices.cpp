#include "session/line_devices.hpp"

#include <bit>
#include <optional>

#include "device/in_process_transport.hpp"
#include "device/usb_discovery.hpp"

namespace flutterscan::session {

std::string connect_controller(const SessionConfig& config, const SessionHooks& hooks,
                               ControllerLink& link, bool& bad_input) {
  const std::string& spec = config.controller.spec;
  device::TransportOpener opener;
  if (spec == "sim") {
    link.virtual_controller = hooks.virtual_controller
                                  ? hooks.virtual_controller
                                  : std::make_shared<device::VirtualController>();
    opener = device::in_process_opener(link.virtual_controller);
    link.description = "virtual controller (firmware core on the sim port)";
  } else {
    auto found = device::find_controllers();
    if (!found.ok()) return "controller: " + found.error().message;
    auto picked = device::pick_controller(
        found.value(), spec == "auto" ? std::nullopt : std::optional<std::string>(spec),
        device::DeviceMode::kApplication);
    if (!picked.ok()) {
      bad_input = picked.error().kind == device::ErrorKind::kNotFound ||
                  picked.error().kind == device::ErrorKind::kAmbiguous;
      return "controller '" + spec + "': " + picked.error().message;
    }
    opener = device::hid_opener(picked.value().serial);
    link.description = "controller " + picked.value().serial;
  }
  auto client = device::ControllerClient::connect(opener);
  if (!client.ok()) return "controller '" + spec + "': " + client.error().message;
  link.client = std::move(client.value());
  auto fail = [&](const char* what, const device::DeviceError& e) {
    return std::string("controller: ") + what + ": " + e.message;
  };
  if (auto r = link.client->disarm(); !r.ok()) return fail("Disarm", r.error());
  // One-of-3 codes are checked as such on the controller; white strobes ("auto") are not.
  const LedCode& code = config.controller.parsed_code;
  bool one_of_n = true;
  for (int t = 0; t < code.length(); ++t) one_of_n = one_of_n && std::popcount(code.mask(t)) == 1;
  if (auto r = link.client->set_code(0, code, one_of_n); !r.ok()) return fail("SetCode", r.error());
  if (auto r = link.client->select_code(0); !r.ok()) return fail("SelectCode", r.error());
  protocol::SetTimingRequest timing{};
  timing.slot_time_us = config.controller.slot_time_us;
  timing.frame_period_us = config.controller.frame_period_us;
  timing.slot_time_source = static_cast<std::uint8_t>(protocol::SlotTimeSource::kFixed);
  if (auto r = link.client->set_timing(timing); !r.ok()) return fail("SetTiming", r.error());
  const auto mode =
      config.controller.sync == "master" ? protocol::SyncMode::kMaster : protocol::SyncMode::kSlave;
  if (auto r = link.client->set_mode(mode, false); !r.ok()) return fail("SetMode", r.error());
  return {};
}

ExposureRecord exposure_record(const device::EventNotice& notice) {
  const protocol::ExposureEvent& e = notice.event;
  return {.frame_counter = e.frame_counter,
          .start_us = e.start_time_us,
          .encoder_delta = e.encoder_delta,
          .slot_time_us = e.slot_time_us,
          .slot_count = e.slot_count,
          .code_id = e.code_id,
          .flags = e.flags};
}

std::unique_ptr<capture::CameraSource> open_camera(const CameraConfig& camera,
                                                   device::VirtualController* controller,
                                                   std::string& error, bool& bad_input) {
  capture::CameraContext context;
  context.controller = controller;
  context.options = camera.options;
  auto source = capture::make_camera(camera.spec, context, error);
  if (!source) {
    bad_input = true;
    return nullptr;
  }
  if (auto p = source->open(); !p.empty()) {
    error = p;
    return nullptr;
  }
  if (auto p = source->configure(camera.settings); !p.empty()) {
    error = "[camera] settings: " + p;
    bad_input = true;
    return nullptr;
  }
  return source;
}

}  // namespace flutterscan::session
