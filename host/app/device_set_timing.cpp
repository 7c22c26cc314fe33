// `flutterscan device set-timing --slot-us N [--frame-period-us N] [--follow-exposure]`.

#include <cstdio>
#include <memory>

#include "app/device_commands.hpp"
#include "app/device_target.hpp"

namespace flutterscan::app {
namespace {

struct TimingOptions {
  DeviceTarget target;
  std::uint32_t slot_us = 0;
  std::uint32_t frame_period_us = 0;
  bool follow_exposure = false;
};

void run(const TimingOptions& options) {
  protocol::SetTimingRequest request{};
  request.slot_time_us = options.slot_us;
  request.frame_period_us = options.frame_period_us;
  request.slot_time_source =
      static_cast<std::uint8_t>(options.follow_exposure ? protocol::SlotTimeSource::kFollowExposure
                                                        : protocol::SlotTimeSource::kFixed);
  DeviceSession session(options.target);
  value_or_throw(session.client().set_timing(request));
  std::printf("slot time %u us%s, frame period %s\n", options.slot_us,
              options.follow_exposure ? " (then following the exposure)" : "",
              options.frame_period_us == 0
                  ? "unset"
                  : (std::to_string(options.frame_period_us) + " us").c_str());
}

}  // namespace

void add_device_set_timing(CLI::App& device) {
  auto options = std::make_shared<TimingOptions>();
  CLI::App* command = device.add_subcommand("set-timing", "Slot time and frame period (idle only)");
  command->add_option("--slot-us", options->slot_us, "slot time, microseconds")
      ->required()
      ->check(CLI::Range(protocol::kMinSlotTimeUs, protocol::kMaxSlotTimeUs));
  command
      ->add_option("--frame-period-us", options->frame_period_us,
                   "master and free-run: frame period, microseconds (1000..10000000)")
      ->check(CLI::Range(protocol::kMinFramePeriodUs, protocol::kMaxFramePeriodUs));
  command->add_flag("--follow-exposure", options->follow_exposure,
                    "slave mode: slot time = previous strobe pulse width / code length");
  add_device_target_options(*command, options->target);
  command->callback([options] { run(*options); });
}

}  // namespace flutterscan::app
