#pragma once
// Transport to a VirtualController in the same process (`--device sim`,
// simulated sessions, tests).

#include <atomic>
#include <memory>

#include "device/transport.hpp"
#include "device/virtual_controller.hpp"

namespace flutterscan::device {

/// \brief A Transport whose device is a VirtualController.
class InProcessTransport final : public Transport {
 public:
  explicit InProcessTransport(std::shared_ptr<VirtualController> controller);

  Expected<Done> write_report(std::span<const std::uint8_t> report) override;
  Expected<std::optional<Report>> read_report(std::chrono::milliseconds timeout) override;
  void close() override { closed_ = true; }
  std::string description() const override;

 private:
  bool reachable() const;
  std::shared_ptr<VirtualController> controller_;
  std::atomic<bool> closed_{false};
};

/// \brief An opener for `controller`: kNotFound while it is unplugged or in its bootloader.
TransportOpener in_process_opener(std::shared_ptr<VirtualController> controller);

}  // namespace flutterscan::device
