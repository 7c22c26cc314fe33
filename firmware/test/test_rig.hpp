#pragma once
// A controller on the simulation port, driven through HID reports like the host drives it.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <string_view>
#include <vector>

#include "flutterscan/common/led_code.hpp"
#include "flutterscan/common/protocol.hpp"
#include "flutterscan/firmware/command_handler.hpp"
#include "flutterscan/firmware/config_store.hpp"
#include "flutterscan/firmware/controller.hpp"
#include "flutterscan/firmware/sim/sim_port.hpp"

namespace flutterscan::firmware::test {

namespace proto = flutterscan::protocol;

/// \brief A reply report.
struct Reply {
  std::array<std::uint8_t, proto::kReportSize> bytes{};
  std::size_t size = 0;

  proto::MessageHeader header() const { return proto::peek_header(bytes); }
  proto::Status status() const { return static_cast<proto::Status>(header().status); }
  std::span<const std::uint8_t> payload() const {
    return std::span<const std::uint8_t>(bytes).subspan(proto::kHeaderSize,
                                                        header().payload_length);
  }
  /// \brief The payload as T (test fails if the length is wrong).
  template <typename T>
  T as() const {
    const auto decoded = proto::decode_payload<T>(payload());
    EXPECT_TRUE(decoded.ok()) << "reply payload of " << payload().size() << " bytes";
    return decoded.value();
  }
};

/// \brief The ceiling of the test board: everything the protocol allows (so the
/// guard's own logic can be tested at any setting, down to the microsecond),
/// and runs joined only when they touch (a minimum off-time of 1 us).
inline LedCeiling protocol_ceiling() {
  LedCeiling ceiling = kProductLedCeiling;
  ceiling.max_on_time_us.fill(proto::kMaxGuardOnTimeUs);
  ceiling.max_duty_permille.fill(proto::kDutyFullScale);
  ceiling.max_current_permille.fill(proto::kBrightnessFullScale);
  ceiling.min_off_time_us = 1;
  return ceiling;
}

/// \brief The default test board: three LEDs on pins 0, 1, 2, the protocol's
/// ceiling, LEDs powered with the MCU (cold after a power-on reset). Tests of
/// the product's boot behaviour use product_like_board().
inline BoardConfig test_board() {
  BoardConfig board;
  board.pins = LedPinMap{3, {0, 1, 2, 3}};
  board.board_id = 0x0405;
  board.firmware_major = 1;
  board.firmware_minor = 2;
  board.firmware_patch = 3;
  board.build_id = 0xC0FFEE01;
  board.ceiling = protocol_ceiling();
  board.leds_powered_with_mcu = true;
  return board;
}

/// \brief The test board with the product's ceiling and LED supply (own 12 V:
/// never cold at boot).
inline BoardConfig product_like_board() {
  BoardConfig board = test_board();
  board.ceiling = kProductLedCeiling;
  board.leds_powered_with_mcu = false;
  return board;
}

/// \brief Guard limits that allow everything the protocol allows.
inline proto::SetGuardRequest permissive_guard() {
  proto::SetGuardRequest r{};
  r.max_on_time_us.fill(proto::kMaxGuardOnTimeUs);
  r.max_duty_permille.fill(proto::kDutyFullScale);
  return r;
}

/// \brief LED `led`'s on-time in `log` between `from_us` and `to_us` (transitions
/// outside the span clamped to it: an LED lit before `from_us` counts from there).
inline std::uint64_t on_time_us(const std::vector<sim::LedTransition>& log, int led,
                                std::uint64_t from_us, std::uint64_t to_us) {
  std::uint64_t total = 0;
  bool on = false;
  std::uint64_t since = from_us;
  for (const auto& w : log) {
    const std::uint64_t t = std::min(std::max(w.time_us, from_us), to_us);
    const bool now_on = ((w.led_mask >> led) & 1u) != 0;
    if (on && !now_on) total += t - since;
    if (!on && now_on) since = t;
    on = now_on;
  }
  if (on) total += to_us - since;
  return total;
}

class Rig {
 public:
  explicit Rig(const BoardConfig& board = test_board(), bool start = true)
      : board_(board), port(board.pins) {
    boot(start);
  }

  /// \brief A fresh controller on the same port (flash and clock kept), as after a reset.
  void reboot(bool start = true) {
    handler_.reset();
    controller_.reset();
    boot(start);
  }

  Controller& controller() { return *controller_; }
  CommandHandler& handler() { return *handler_; }

  Reply send_raw(std::span<const std::uint8_t> request) {
    Reply reply;
    reply.size = handler_->handle(request, reply.bytes);
    EXPECT_EQ(reply.size, proto::kReportSize);
    return reply;
  }

  template <typename T>
  Reply send(proto::Command command, const T& payload) {
    std::array<std::uint8_t, proto::kReportSize> report{};
    EXPECT_EQ(proto::encode_request(command, ++sequence_, payload, report), proto::kReportSize);
    const Reply reply = send_raw(report);
    EXPECT_EQ(reply.header().command, static_cast<std::uint8_t>(command));
    EXPECT_EQ(reply.header().sequence, sequence_);
    return reply;
  }

  Reply send(proto::Command command) {
    std::array<std::uint8_t, proto::kReportSize> report{};
    EXPECT_EQ(proto::encode_request(command, ++sequence_, report), proto::kReportSize);
    const Reply reply = send_raw(report);
    EXPECT_EQ(reply.header().command, static_cast<std::uint8_t>(command));
    EXPECT_EQ(reply.header().sequence, sequence_);
    return reply;
  }

  /// \brief Uploads `code` under `id` in as many chunks as it needs; the last reply's status.
  proto::Status upload(std::uint8_t id, const LedCode& code, std::uint8_t flags = 0) {
    proto::Status status = proto::Status::kOk;
    for (int first = 0; first < code.length();
         first += static_cast<int>(proto::kSlotsPerCodeChunk)) {
      proto::SetCodeRequest r{};
      r.code_id = id;
      r.led_count = static_cast<std::uint8_t>(code.leds());
      r.total_slots = static_cast<std::uint16_t>(code.length());
      r.first_slot = static_cast<std::uint16_t>(first);
      const int count = std::min<int>(code.length() - first, proto::kSlotsPerCodeChunk);
      r.slot_count = static_cast<std::uint8_t>(count);
      r.flags = flags;
      for (int i = 0; i < count; ++i) r.masks[static_cast<std::size_t>(i)] = code.mask(first + i);
      status = send(proto::Command::kSetCode, r).status();
      if (status != proto::Status::kOk) break;
    }
    return status;
  }

  proto::Status upload(std::uint8_t id, std::string_view digits, int leds, std::uint8_t flags = 0) {
    const auto code = LedCode::parse(digits, leds);
    EXPECT_TRUE(code.ok());
    return upload(id, code.value(), flags);
  }

  proto::Status select(std::uint8_t id) {
    return send(proto::Command::kSelectCode, proto::SelectCodeRequest{id, {}}).status();
  }

  proto::Status set_timing(std::uint32_t slot_us, std::uint32_t period_us = 0,
                           proto::SlotTimeSource source = proto::SlotTimeSource::kFixed) {
    return send(proto::Command::kSetTiming,
                proto::SetTimingRequest{slot_us, period_us, static_cast<std::uint8_t>(source), {}})
        .status();
  }

  proto::Status set_mode(proto::SyncMode mode) {
    return send(proto::Command::kSetMode,
                proto::SetModeRequest{static_cast<std::uint8_t>(mode), 0, {}})
        .status();
  }

  proto::Status arm() { return send(proto::Command::kArm).status(); }
  proto::Status disarm() { return send(proto::Command::kDisarm).status(); }
  proto::StatusReply status() { return send(proto::Command::kGetStatus).as<proto::StatusReply>(); }

  /// \brief Every exposure event waiting, oldest first.
  std::vector<proto::ExposureEvent> events() {
    std::vector<proto::ExposureEvent> out;
    proto::ExposureEvent event;
    while (controller_->pop_event(event)) out.push_back(event);
    return out;
  }

  /// \brief The settings as their config image (for "nothing changed" comparisons).
  std::vector<std::uint8_t> settings_snapshot() {
    const ConfigImage image = encode_config(controller_->settings());
    const auto* bytes = reinterpret_cast<const std::uint8_t*>(&image);
    return {bytes, bytes + sizeof(image)};
  }

 private:
  void boot(bool start) {
    // Heap-held in the test rig only: GCC 12 at -O3 warns falsely that an
    // std::optional<Controller>'s reference member may be read uninitialised.
    controller_ = std::make_unique<Controller>(port, board_);
    handler_ = std::make_unique<CommandHandler>(*controller_);
    if (start) controller_->start();
  }

  BoardConfig board_;

 public:
  sim::SimPort port;

 private:
  std::unique_ptr<Controller> controller_;
  std::unique_ptr<CommandHandler> handler_;
  std::uint8_t sequence_ = 0;
};

}  // namespace flutterscan::firmware::test
