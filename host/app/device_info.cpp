// `flutterscan device info`: identity, versions, limits and features (GetInfo).

#include <cstdio>
#include <memory>
#include <string>

#include "app/device_commands.hpp"
#include "app/device_target.hpp"

namespace flutterscan::app {
namespace {

std::string feature_names(std::uint32_t features) {
  static constexpr std::pair<std::uint32_t, const char*> kNames[] = {
      {protocol::kFeatureSlaveSync, "slave-sync"},
      {protocol::kFeatureMasterSync, "master-sync"},
      {protocol::kFeatureFreeRun, "free-run"},
      {protocol::kFeatureFollowExposure, "follow-exposure"},
      {protocol::kFeatureEncoder, "encoder"},
      {protocol::kFeatureBrightness, "brightness"},
      {protocol::kFeatureThermalGuard, "thermal-guard"},
      {protocol::kFeatureConfigFlash, "config-flash"},
      {protocol::kFeatureDfu, "dfu"},
  };
  std::string out;
  for (const auto& [bit, name] : kNames)
    if (features & bit) out += (out.empty() ? "" : " ") + std::string(name);
  return out.empty() ? "none" : out;
}

void print_info(const DeviceTarget& target) {
  DeviceSession session(target);
  const protocol::InfoReply info = session.client().info();
  std::printf("controller  %s\n", session.client().description().c_str());
  std::printf("firmware    %s (build %08X)\n",
              version_text(info.firmware_major, info.firmware_minor, info.firmware_patch).c_str(),
              info.build_id);
  std::printf("protocol    %u.%u (this flutterscan: %u.%u)\n", info.protocol_major,
              info.protocol_minor, protocol::kProtocolMajor, protocol::kProtocolMinor);
  std::printf("board       %u, %u LEDs, %u code slots, codes up to %u slots\n", info.board_id,
              info.led_count, info.max_codes, info.max_slots);
  std::printf("slot time   %u..%u us\n", info.min_slot_time_us, info.max_slot_time_us);
  std::printf("features    %s\n", feature_names(info.features).c_str());
}

}  // namespace

void add_device_info(CLI::App& device) {
  auto target = std::make_shared<DeviceTarget>();
  CLI::App* command = device.add_subcommand("info", "Versions, board, limits and features");
  add_device_target_options(*command, *target);
  command->callback([target] { print_info(*target); });
}

}  // namespace flutterscan::app
