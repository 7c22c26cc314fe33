#include "flutterscan/firmware/command_handler.hpp"

namespace flutterscan::firmware {

using protocol::Command;
using protocol::Status;

namespace {

/// Writes a reply to `header`'s command: `result`'s value as the payload on
/// success, an empty payload with its status otherwise.
template <typename T>
std::size_t reply_with(const protocol::MessageHeader& header, const Result<T, Status>& result,
                       std::span<std::uint8_t> reply) {
  if (!result.ok())
    return protocol::encode_empty(header.command, header.sequence, result.error(), reply);
  return protocol::encode_message(header.command, header.sequence, Status::kOk, result.value(),
                                  reply);
}

std::size_t reply_status(const protocol::MessageHeader& header, Status status,
                         std::span<std::uint8_t> reply) {
  return protocol::encode_empty(header.command, header.sequence, status, reply);
}

/// Decodes a payload of type T and calls `apply` with it, replying with the
/// decode error if any or whatever `apply` returns.
template <typename T, typename Apply>
std::size_t with_payload(const protocol::MessageView& message, std::span<std::uint8_t> reply,
                         Apply apply) {
  const auto request = protocol::decode_payload<T>(message.payload);
  if (!request.ok()) return reply_status(message.header, request.error(), reply);
  return apply(request.value());
}

}  // namespace

std::size_t CommandHandler::handle(std::span<const std::uint8_t> request,
                                   std::span<std::uint8_t> reply) {
  const auto parsed = protocol::parse_request(request);
  if (!parsed.ok()) return reply_status(protocol::peek_header(request), parsed.error(), reply);
  const protocol::MessageView& message = parsed.value();
  const protocol::MessageHeader& header = message.header;
  if (!protocol::is_request_command(header.command))
    return reply_status(header, Status::kUnknownCommand, reply);

  auto status_only = [&](Status status) { return reply_status(header, status, reply); };
  auto empty_then = [&](auto apply) {
    const Status length = protocol::expect_empty_payload(message.payload);
    if (length != Status::kOk) return status_only(length);
    return apply();
  };

  switch (static_cast<Command>(header.command)) {
    case Command::kGetInfo:
      return empty_then([&] {
        count_query();
        return protocol::encode_message(header.command, header.sequence, Status::kOk,
                                        controller_.info(), reply);
      });
    case Command::kSetCode:
      return with_payload<protocol::SetCodeRequest>(message, reply, [&](const auto& r) {
        return reply_with(header, controller_.set_code_chunk(r), reply);
      });
    case Command::kSelectCode:
      return with_payload<protocol::SelectCodeRequest>(message, reply, [&](const auto& r) {
        return reply_with(header, controller_.select_code(r), reply);
      });
    case Command::kSetTiming:
      return with_payload<protocol::SetTimingRequest>(
          message, reply, [&](const auto& r) { return status_only(controller_.set_timing(r)); });
    case Command::kSetMode:
      return with_payload<protocol::SetModeRequest>(
          message, reply, [&](const auto& r) { return status_only(controller_.set_mode(r)); });
    case Command::kSetBrightness:
      return with_payload<protocol::SetBrightnessRequest>(message, reply, [&](const auto& r) {
        return status_only(controller_.set_brightness(r));
      });
    case Command::kSetGuard:
      return with_payload<protocol::SetGuardRequest>(
          message, reply, [&](const auto& r) { return status_only(controller_.set_guard(r)); });
    case Command::kArm:
      return empty_then([&] { return status_only(controller_.arm()); });
    case Command::kDisarm:
      return empty_then([&] { return status_only(controller_.disarm()); });
    case Command::kGetStatus:
      return empty_then([&] {
        count_query();
        return protocol::encode_message(header.command, header.sequence, Status::kOk,
                                        controller_.status(), reply);
      });
    case Command::kSelfTest:
      return with_payload<protocol::SelfTestRequest>(message, reply, [&](const auto& r) {
        return reply_with(header, controller_.self_test(r), reply);
      });
    case Command::kSaveConfig:
      return empty_then([&] { return reply_with(header, controller_.save_config(), reply); });
    case Command::kEnterBootloader:
      return with_payload<protocol::EnterBootloaderRequest>(message, reply, [&](const auto& r) {
        return status_only(controller_.enter_bootloader(r));
      });
    case Command::kExposureEvent:
      break;  // not a request (is_request_command excludes it)
  }
  return status_only(Status::kUnknownCommand);
}

std::size_t CommandHandler::next_event_report(std::span<std::uint8_t> report) {
  if (report.size() < protocol::kReportSize) return 0;
  protocol::ExposureEvent event;
  if (!controller_.pop_event(event)) return 0;
  return protocol::encode_message(static_cast<std::uint8_t>(Command::kExposureEvent),
                                  event_sequence_++, Status::kOk, event, report);
}

}  // namespace flutterscan::firmware
