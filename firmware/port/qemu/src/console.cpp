#include "flutterscan/firmware/qemu/console.hpp"

#include "flutterscan/common/led_code.hpp"

namespace flutterscan::firmware::qemu {

using protocol::Command;
using protocol::Status;

namespace {

/// A reply line assembled in a fixed buffer (no heap, no printf); ends in '\n'.
class Line {
 public:
  Line& operator<<(std::string_view text) {
    for (const char c : text) put(c);
    return *this;
  }
  Line& dec(std::uint64_t value) {
    std::array<char, 20> digits{};
    std::size_t n = 0;
    do {
      digits[n++] = static_cast<char>('0' + value % 10);
      value /= 10;
    } while (value != 0);
    while (n > 0) put(digits[--n]);
    return *this;
  }
  Line& sdec(std::int64_t value) {
    if (value < 0) {
      put('-');
      return dec(0u - static_cast<std::uint64_t>(value));
    }
    return dec(static_cast<std::uint64_t>(value));
  }
  Line& hex32(std::uint32_t value) {
    *this << "0x";
    for (int shift = 28; shift >= 0; shift -= 4) put("0123456789abcdef"[(value >> shift) & 0xFu]);
    return *this;
  }
  /// The line with its newline.
  std::string_view finish() {
    put('\n');
    return {buffer_.data(), length_};
  }

 private:
  void put(char c) {
    // Keep the last byte for the newline.
    if (length_ + 1 < buffer_.size()) buffer_[length_++] = c;
  }
  std::array<char, 200> buffer_{};
  std::size_t length_ = 0;
};

std::string_view trim(std::string_view text) {
  while (!text.empty() && (text.front() == ' ' || text.front() == '\t')) text.remove_prefix(1);
  while (!text.empty() && (text.back() == ' ' || text.back() == '\t')) text.remove_suffix(1);
  return text;
}

/// The first `n` characters of `text` (all if shorter). Unlike substr, never
/// throws: std::__throw_* would pull abort() and malloc into the image.
std::string_view head(std::string_view text, std::size_t n) {
  return {text.data(), n < text.size() ? n : text.size()};
}

/// Splits off the first word of `text` (which keeps the rest, trimmed).
std::string_view next_word(std::string_view& text) {
  text = trim(text);
  std::size_t end = 0;
  while (end < text.size() && text[end] != ' ' && text[end] != '\t') ++end;
  const std::string_view word = head(text, end);
  text.remove_prefix(end);
  text = trim(text);
  return word;
}

bool parse_u32(std::string_view text, std::uint32_t& out) {
  if (text.empty() || text.size() > 10) return false;
  std::uint64_t value = 0;
  for (const char c : text) {
    if (c < '0' || c > '9') return false;
    value = value * 10 + static_cast<std::uint64_t>(c - '0');
  }
  if (value > 0xFFFFFFFFu) return false;
  out = static_cast<std::uint32_t>(value);
  return true;
}

bool parse_i32(std::string_view text, std::int32_t& out) {
  const bool negative = !text.empty() && text.front() == '-';
  if (negative || (!text.empty() && text.front() == '+')) text.remove_prefix(1);
  std::uint32_t magnitude = 0;
  if (!parse_u32(text, magnitude) || magnitude > 0x7FFFFFFFu) return false;
  out = negative ? -static_cast<std::int32_t>(magnitude) : static_cast<std::int32_t>(magnitude);
  return true;
}

/// The payload of a reply as a T (zeroed if it is not one).
template <protocol::WireStruct T>
T reply_payload(std::span<const std::uint8_t> report) {
  const auto message = protocol::parse_message(report);
  if (!message.ok()) return T{};
  const auto payload = protocol::decode_payload<T>(message.value().payload);
  return payload.ok() ? payload.value() : T{};
}

/// Allowance on top of a sequence's own duration before the console gives up on it.
constexpr std::uint64_t kSequenceMarginUs = 100'000;

}  // namespace

// ---------------------------------------------------------------------------
// Lines

void Console::feed(char c) {
  if (c == '\n' || c == '\r') {
    if (line_overflow_) {
      fail("line longer than 300 characters");
    } else if (!trim({line_.data(), line_length_}).empty()) {
      execute({line_.data(), line_length_});
    }
    line_length_ = 0;
    line_overflow_ = false;
    return;
  }
  if (line_length_ < line_.size())
    line_[line_length_++] = c;
  else
    line_overflow_ = true;
}

void Console::execute(std::string_view line) {
  std::string_view args = line;
  const std::string_view command = next_word(args);
  if (command == "help") {
    cmd_help();
  } else if (command == "version" && args.empty()) {
    cmd_version();
  } else if (command == "status" && args.empty()) {
    cmd_status();
  } else if (command == "selftest") {
    cmd_selftest(args);
  } else if (command == "expose") {
    cmd_expose(args);
  } else if (command == "encoder") {
    cmd_encoder(args);
  } else {
    Line out;
    device_.write((out << "error: unknown command '" << head(line, 40) << "' (try help)").finish());
  }
}

void Console::fail(std::string_view what, Status status) {
  Line out;
  device_.write((out << "error: " << what << ": " << protocol::status_text(status)).finish());
}

void Console::fail(std::string_view what) {
  Line out;
  device_.write((out << "error: " << what).finish());
}

// ---------------------------------------------------------------------------
// Requests

Status Console::transact(std::span<const std::uint8_t> request, Report& reply) {
  reply.fill(0);
  if (device_.handle(handler_, request, reply) < protocol::kHeaderSize) return Status::kBadLength;
  return static_cast<Status>(protocol::peek_header(reply).status);
}

template <typename T>
Status Console::request(Command command, const T& payload, Report& reply) {
  Report report{};
  protocol::encode_request(command, next_sequence(), payload, report);
  return transact(report, reply);
}

Status Console::request(Command command, Report& reply) {
  Report report{};
  protocol::encode_request(command, next_sequence(), report);
  return transact(report, reply);
}

// ---------------------------------------------------------------------------
// Commands

void Console::cmd_help() {
  device_.write(
      "commands: version | status | selftest [STEP_US] | expose CODE SLOT_US | encoder COUNTS | "
      "help\n");
}

void Console::cmd_version() {
  Report reply;
  const Status status = request(Command::kGetInfo, reply);
  if (status != Status::kOk) return fail("GetInfo", status);
  const auto info = reply_payload<protocol::InfoReply>(reply);
  Line out;
  out << "version firmware ";
  out.dec(info.firmware_major) << ".";
  out.dec(info.firmware_minor) << ".";
  out.dec(info.firmware_patch) << " protocol ";
  out.dec(info.protocol_major) << ".";
  out.dec(info.protocol_minor) << " board ";
  out.dec(info.board_id) << " leds ";
  out.dec(info.led_count) << " build ";
  out.hex32(info.build_id);
  device_.write(out.finish());
}

void Console::cmd_status() {
  Report reply;
  const Status status = request(Command::kGetStatus, reply);
  if (status != Status::kOk) return fail("GetStatus", status);
  const auto s = reply_payload<protocol::StatusReply>(reply);
  Line out;
  out << "status state " << protocol::controller_state_name(s.state) << " mode "
      << protocol::sync_mode_name(s.sync_mode) << " code ";
  if (s.active_code_id == protocol::kNoCode)
    out << "none";
  else
    out.dec(s.active_code_id);
  out << " slot_us ";
  out.dec(s.slot_time_us) << " frames ";
  out.dec(s.frame_counter) << " missed ";
  out.dec(s.missed_triggers) << " overruns ";
  out.dec(s.overruns) << " guard_hits ";
  out.dec(s.guard_hits) << " fault ";
  out.dec(s.last_fault) << " uptime_us ";
  out.dec(s.uptime_us) << " led_writes ";
  out.dec(device_.led_write_count());
  device_.write(out.finish());
}

void Console::cmd_selftest(std::string_view args) {
  std::uint32_t step_us = 1000;
  if (!args.empty() && !parse_u32(args, step_us))
    return fail("usage: selftest [STEP_US] (STEP_US a whole number of microseconds)");
  const std::uint32_t first = device_.led_write_count();
  Report reply;
  const Status status = request(Command::kSelfTest, protocol::SelfTestRequest{step_us}, reply);
  if (status != Status::kOk) return fail("SelfTest", status);
  const auto result = reply_payload<protocol::SelfTestReply>(reply);

  // Wait until the controller reports the self test finished.
  const std::uint64_t deadline = device_.now_us() + result.duration_us + kSequenceMarginUs;
  for (;;) {
    Report status_reply;
    if (request(Command::kGetStatus, status_reply) != Status::kOk) return fail("GetStatus");
    const auto s = reply_payload<protocol::StatusReply>(status_reply);
    if ((s.flags & protocol::kStatusSelfTestRunning) == 0) break;
    if (device_.now_us() > deadline) return fail("self test did not finish");
    device_.wait();
  }
  Line out;
  out << "selftest ok leds ";
  out.dec(result.leds_stepped) << " step_us ";
  out.dec(step_us) << " first_write ";
  out.dec(first) << " writes ";
  out.dec(device_.led_write_count() - first);
  device_.write(out.finish());
}

void Console::cmd_expose(std::string_view args) {
  const std::string_view digits = next_word(args);
  const std::string_view slot_text = next_word(args);
  std::uint32_t slot_us = 0;
  if (digits.empty() || !args.empty() || !parse_u32(slot_text, slot_us))
    return fail("usage: expose CODE SLOT_US (e.g. expose 124124 100)");

  Report reply;
  Status status = request(Command::kGetInfo, reply);
  if (status != Status::kOk) return fail("GetInfo", status);
  const int leds = reply_payload<protocol::InfoReply>(reply).led_count;
  const auto code = LedCode::parse(digits, leds);
  if (!code.ok()) {
    std::array<char, 120> text{};
    const std::size_t n = describe(code.error(), text);
    return fail({text.data(), n});
  }

  // Upload as the host tool would: SetCode chunks, then select, time, mode, arm.
  constexpr std::uint8_t kCodeId = 0;
  const LedCode& c = code.value();
  const auto total = static_cast<std::uint16_t>(c.length());
  for (std::uint16_t first = 0; first < total;) {
    protocol::SetCodeRequest chunk{};
    chunk.code_id = kCodeId;
    chunk.led_count = static_cast<std::uint8_t>(leds);
    chunk.total_slots = total;
    chunk.first_slot = first;
    const std::size_t left = static_cast<std::size_t>(total - first);
    const std::size_t count =
        left < protocol::kSlotsPerCodeChunk ? left : protocol::kSlotsPerCodeChunk;
    chunk.slot_count = static_cast<std::uint8_t>(count);
    chunk.flags = protocol::kCodeFlagOneOfN;
    for (std::size_t i = 0; i < count; ++i) chunk.masks[i] = c.mask(static_cast<int>(first + i));
    status = request(Command::kSetCode, chunk, reply);
    if (status != Status::kOk) return fail("SetCode", status);
    first = static_cast<std::uint16_t>(first + count);
  }
  status = request(Command::kSelectCode, protocol::SelectCodeRequest{kCodeId, {}}, reply);
  if (status != Status::kOk) return fail("SelectCode", status);
  status = request(Command::kSetTiming,
                   protocol::SetTimingRequest{
                       slot_us, 0, static_cast<std::uint8_t>(protocol::SlotTimeSource::kFixed), {}},
                   reply);
  if (status != Status::kOk) return fail("SetTiming", status);
  status = request(
      Command::kSetMode,
      protocol::SetModeRequest{static_cast<std::uint8_t>(protocol::SyncMode::kSlave), 0, {}},
      reply);
  if (status != Status::kOk) return fail("SetMode", status);
  status = request(Command::kArm, reply);
  if (status != Status::kOk) return fail("Arm", status);

  // The console plays the camera: strobe up starts the exposure.
  const std::uint32_t first_write = device_.led_write_count();
  const std::uint64_t deadline =
      device_.now_us() + static_cast<std::uint64_t>(total) * slot_us + kSequenceMarginUs;
  device_.set_strobe(true);
  Report event_report{};
  bool have_event = false;
  while (!(have_event = handler_.next_event_report(event_report) != 0) &&
         device_.now_us() <= deadline)
    device_.wait();
  const std::uint32_t writes = device_.led_write_count() - first_write;
  device_.set_strobe(false);
  Report disarm_reply;
  const Status disarmed = request(Command::kDisarm, disarm_reply);
  if (!have_event) return fail("no exposure event: the sequence did not finish");
  if (disarmed != Status::kOk) return fail("Disarm", disarmed);

  const auto event = reply_payload<protocol::ExposureEvent>(event_report);
  if (event.flags & protocol::kEventGuardHit)
    return fail("exposure refused by the thermal guard (LEDs stayed off)");
  Line out;
  out << "done frame ";
  out.dec(event.frame_counter) << " slots ";
  out.dec(event.slot_count) << " slot_us ";
  out.dec(event.slot_time_us) << " first_write ";
  out.dec(first_write) << " writes ";
  out.dec(writes);
  device_.write(out.finish());
}

void Console::cmd_encoder(std::string_view args) {
  std::int32_t counts = 0;
  if (!parse_i32(args, counts)) return fail("usage: encoder COUNTS (a signed whole number)");
  device_.add_encoder_counts(counts);
  Line out;
  device_.write((out << "encoder ").sdec(counts).finish());
}

}  // namespace flutterscan::firmware::qemu
