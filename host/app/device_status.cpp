// `flutterscan device status`: state, codes, timing and counters (GetStatus).

#include <cstdio>
#include <memory>
#include <string>

#include "app/device_commands.hpp"
#include "app/device_target.hpp"

namespace flutterscan::app {
namespace {

const char* fault_name(std::uint8_t fault) {
  switch (static_cast<protocol::FaultCode>(fault)) {
    case protocol::FaultCode::kNone:
      return "none";
    case protocol::FaultCode::kWatchdogReset:
      return "watchdog reset";
    case protocol::FaultCode::kSlotTimer:
      return "slot timer";
    case protocol::FaultCode::kPort:
      return "hardware layer";
  }
  return "unknown";
}

std::string code_id_text(std::uint8_t id) {
  return id == protocol::kNoCode ? "none" : std::to_string(id);
}

std::string stored_text(std::uint8_t bits) {
  std::string out;
  for (int id = 0; id < 8; ++id)
    if (bits & (1u << id)) out += (out.empty() ? "" : ", ") + std::to_string(id);
  return out.empty() ? "none" : out;
}

std::string flags_text(std::uint8_t flags) {
  std::string out;
  auto add = [&](std::uint8_t bit, const char* name) {
    if (flags & bit) out += (out.empty() ? "" : ", ") + std::string(name);
  };
  add(protocol::kStatusConfigFromFlash, "config loaded from flash");
  add(protocol::kStatusConfigCorrupt, "flash config corrupt (defaults in use)");
  add(protocol::kStatusSelfTestRunning, "self test running");
  add(protocol::kStatusUploadInProgress, "code upload unfinished");
  return out.empty() ? "none" : out;
}

void print_status(const DeviceTarget& target) {
  DeviceSession session(target);
  const auto s = value_or_throw(session.client().status());
  std::printf("state            %s\n", protocol::controller_state_name(s.state));
  std::printf("mode             %s\n", protocol::sync_mode_name(s.sync_mode));
  std::printf("active code      %s\n", code_id_text(s.active_code_id).c_str());
  std::printf("pending code     %s\n", code_id_text(s.pending_code_id).c_str());
  std::printf("codes stored     %s\n", stored_text(s.codes_stored).c_str());
  std::printf("slot time        %u us\n", s.slot_time_us);
  std::printf("frames           %u\n", s.frame_counter);
  std::printf("missed triggers  %u\n", s.missed_triggers);
  std::printf("overruns         %u\n", s.overruns);
  std::printf("guard hits       %u\n", s.guard_hits);
  std::printf("events dropped   %u\n", s.events_dropped);
  std::printf("last fault       %s\n", fault_name(s.last_fault));
  std::printf("flags            %s\n", flags_text(s.flags).c_str());
  std::printf("uptime           %.3f s\n", static_cast<double>(s.uptime_us) / 1e6);
}

}  // namespace

void add_device_status(CLI::App& device) {
  auto target = std::make_shared<DeviceTarget>();
  CLI::App* command = device.add_subcommand("status", "State, codes, timing and counters");
  add_device_target_options(*command, *target);
  command->callback([target] { print_status(*target); });
}

}  // namespace flutterscan::app
