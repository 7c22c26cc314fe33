#include "device/in_process_transport.hpp"

#include <thread>

namespace flutterscan::device {

namespace {

/// Sleep between polls of the virtual IN queue.
constexpr auto kPollInterval = std::chrono::microseconds(200);

}  // namespace

InProcessTransport::InProcessTransport(std::shared_ptr<VirtualController> controller)
    : controller_(std::move(controller)) {}

bool InProcessTransport::reachable() const {
  return !closed_ && controller_->plugged_in() && !controller_->in_bootloader();
}

Expected<Done> InProcessTransport::write_report(std::span<const std::uint8_t> report) {
  if (report.size() > protocol::kReportSize)
    return fail(ErrorKind::kBadInput, "report of " + std::to_string(report.size()) +
                                          " bytes is longer than " +
                                          std::to_string(protocol::kReportSize));
  if (closed_ || !controller_->write_report(report))
    return fail(ErrorKind::kGone, description() + " is gone (unplugged)");
  return done();
}

Expected<std::optional<Report>> InProcessTransport::read_report(std::chrono::milliseconds timeout) {
  using Out = Expected<std::optional<Report>>;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    if (!reachable())
      return fail<std::optional<Report>>(ErrorKind::kGone, description() + " is gone (unplugged)");
    if (auto report = controller_->read_report()) return Out::success(*report);
    if (std::chrono::steady_clock::now() >= deadline) return Out::success(std::nullopt);
    std::this_thread::sleep_for(kPollInterval);
  }
}

std::string InProcessTransport::description() const {
  return "virtual controller " + controller_->serial_number();
}

TransportOpener in_process_opener(std::shared_ptr<VirtualController> controller) {
  return [controller]() -> Expected<std::unique_ptr<Transport>> {
    if (!controller->plugged_in() || controller->in_bootloader())
      return fail<std::unique_ptr<Transport>>(
          ErrorKind::kNotFound,
          "virtual controller " + controller->serial_number() + " is not connected");
    return Expected<std::unique_ptr<Transport>>::success(
        std::make_unique<InProcessTransport>(controller));
  };
}

}  // namespace flutterscan::device
