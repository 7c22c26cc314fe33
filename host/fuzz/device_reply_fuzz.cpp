// libFuzzer target: the host's parsing of what a controller sends, fed as a
// hostile or broken device would send it.
//
// Two targets from this file. device_reply (byte 0 odd / even):
// - odd: the DFU request sequence (dfu_flasher.hpp) against a bootloader whose
//   every GETSTATUS and UPLOAD reply and every transfer result is scripted:
//   dfu_get_status, dfu_make_idle, dfu_download of a small image, dfu_upload.
// - even: reports one after the other (a length byte, then the bytes) through
//   the parsers the client uses on each: parse_message, the status texts, and
//   decode_payload of every reply type and the exposure event.
// device_client (FLUTTERSCAN_FUZZ_DEVICE_CLIENT; the whole input): the
//   controller client (host/device/controller_client.hpp) over a fake Transport.
//   Each request the client writes lets the device answer with the next
//   scripted IN reports (1-3 of them, rarely none; any bytes: replies, exposure
//   events, junk), mostly with the command and sequence bytes of the request
//   copied in so that they get past the matching and into the parsers. The
//   client connects (GetInfo handshake), then runs up to 8 commands chosen by
//   the input and reads the events that came in. When the script runs out the
//   device is gone. Its reader thread and reply waits (300 us each) make it
//   slower than device_reply.
// Oracles: every failure carries a message; the flasher never sleeps more than
// kMaxDfuPollSleep at a time nor kMaxDfuBusyWait on one block (a device asking
// for 4.6 hours per poll would have hung `flutterscan flash`); UPLOAD returns at
// most what was asked; the client never reports more events than the device sent.

#include <condition_variable>
#include <deque>
#include <mutex>

#include "device/controller_client.hpp"
#include "device/dfu_flasher.hpp"
#include "fuzz_support.hpp"

using namespace flutterscan;
using namespace flutterscan::device;
using protocol::Command;

namespace {

/// A device whose IN reports come from the input, released request by request.
class ScriptedTransport final : public Transport {
 public:
  /// `events_sent` outlives the transport (the client's reader thread may drop it first).
  ScriptedTransport(fuzz::Bytes& in, std::shared_ptr<std::uint64_t> events_sent)
      : in_(in), events_sent_(std::move(events_sent)) {}

  Expected<Done> write_report(std::span<const std::uint8_t> report) override {
    std::lock_guard lock(mutex_);
    if (gone_) return fail(ErrorKind::kGone, "scripted device gone");
    if (in_.left() < 2) {
      gone_ = true;
      changed_.notify_all();
      return fail(ErrorKind::kGone, "scripted device gone");
    }
    // how: bits 0-1 the replies (1..3; 0xFF: none, the client times out, rarely so
    // that executions stay fast); bits 2-4: which replies do not echo the request.
    const std::uint8_t how = in_.u8();
    const int replies = how == 0xFF ? 0 : 1 + (how & 3) % 3;
    for (int r = 0; r < replies; ++r) {
      Report out{};
      const auto body = in_.take(out.size());
      std::copy(body.begin(), body.end(), out.begin());
      if (((how >> (2 + r)) & 1) == 0) {  // echo command and sequence: the awaited reply
        out[0] = report[0];
        out[1] = report[1];
      }
      if (out[0] == static_cast<std::uint8_t>(Command::kExposureEvent)) ++*events_sent_;
      queue_.push_back(out);
    }
    changed_.notify_all();
    return done();
  }

  Expected<std::optional<Report>> read_report(std::chrono::milliseconds timeout) override {
    std::unique_lock lock(mutex_);
    // Short waits: the client's destructor joins its reader thread, which may be in here.
    changed_.wait_for(lock,
                      std::min<std::chrono::microseconds>(timeout, std::chrono::microseconds(100)),
                      [&] { return !queue_.empty() || gone_; });
    if (!queue_.empty()) {
      Report r = queue_.front();
      queue_.pop_front();
      return Expected<std::optional<Report>>::success(r);
    }
    // The input is read on the writing thread only: this is the client's reader thread.
    if (gone_) return fail<std::optional<Report>>(ErrorKind::kGone, "scripted device gone");
    return Expected<std::optional<Report>>::success(std::nullopt);
  }

  void close() override {
    std::lock_guard lock(mutex_);
    gone_ = true;
    changed_.notify_all();
  }
  std::string description() const override { return "scripted device"; }

 private:
  fuzz::Bytes& in_;
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<Report> queue_;
  bool gone_ = false;
  std::shared_ptr<std::uint64_t> events_sent_;  ///< written on the writing thread only
};

template <typename T>
void check_outcome(const Expected<T>& result, const char* what) {
  fuzz::trace(std::string(what) + ": " + (result.ok() ? "ok" : result.error().message));
  if (!result.ok())
    FUZZ_CHECK(!result.error().message.empty(), std::string(what) + " failed without a message");
}

[[maybe_unused]] void fuzz_client(fuzz::Bytes& in) {
  auto events_sent = std::make_shared<std::uint64_t>(0);
  bool opened = false;
  ClientOptions options;
  // Short: a reply that does not come (half the scripted ones do not echo the request)
  // costs this much wall time, and it was most of an execution at 3 ms.
  options.reply_timeout = std::chrono::microseconds(300);
  options.retries = 0;
  in.u8();  // (was: retries; kept so that the corpus stays valid)
  options.reconnect = false;
  options.event_queue_limit = 8;
  auto opener = [&]() -> Expected<std::unique_ptr<Transport>> {
    if (opened) return fail<std::unique_ptr<Transport>>(ErrorKind::kGone, "opened once");
    opened = true;
    return Expected<std::unique_ptr<Transport>>::success(
        std::make_unique<ScriptedTransport>(in, events_sent));
  };
  auto client = ControllerClient::connect(opener, options);
  if (!client.ok()) {
    fuzz::trace("connect: " + client.error().message);
    FUZZ_CHECK(!client.error().message.empty(), "connect failed without a message");
    return;
  }
  ControllerClient& c = *client.value();
  std::uint64_t events_seen = 0;
  for (int i = 0; i < 8 && c.connected(); ++i) {
    switch (in.u8() % 12) {
      case 0:
        check_outcome(c.status(), "status");
        break;
      case 1:
        check_outcome(c.select_code(in.u8()), "select_code");
        break;
      case 2: {
        auto code = LedCode::parse("124124421241", 3, CodeRule::kOneOfN);
        if (code.ok()) check_outcome(c.set_code(in.u8() % 4, code.value(), true), "set_code");
        break;
      }
      case 3:
        check_outcome(c.arm(), "arm");
        break;
      case 4:
        check_outcome(c.disarm(), "disarm");
        break;
      case 5:
        check_outcome(c.self_test(100), "self_test");
        break;
      case 6:
        check_outcome(c.save_config(), "save_config");
        break;
      case 7: {
        protocol::SetTimingRequest t{};
        t.slot_time_us = 100;
        check_outcome(c.set_timing(t), "set_timing");
        break;
      }
      case 8:
        check_outcome(c.set_mode(protocol::SyncMode::kSlave, in.flag()), "set_mode");
        break;
      case 9: {
        protocol::SetGuardRequest g{};
        g.max_on_time_us.fill(1000);
        g.max_duty_permille.fill(500);
        check_outcome(c.set_guard(g), "set_guard");
        break;
      }
      case 10: {
        Report raw{};
        raw[0] = in.u8();
        check_outcome(c.exchange_raw(raw), "exchange_raw");
        break;
      }
      default:
        while (c.next_event(std::chrono::milliseconds(0))) ++events_seen;
        break;
    }
  }
  while (c.next_event(std::chrono::milliseconds(0))) ++events_seen;
  const ClientStats stats = c.stats();
  FUZZ_CHECK(stats.events <= *events_sent, "the client counted " + std::to_string(stats.events) +
                                               " events of " + std::to_string(*events_sent) +
                                               " sent");
  FUZZ_CHECK(events_seen <= stats.events, "more events read than received");
}

/// A bootloader whose every reply comes from the input.
class ScriptedBootloader final : public DfuControl {
 public:
  explicit ScriptedBootloader(fuzz::Bytes& in) : in_(in) {}

  Expected<Done> control_out(DfuRequest, std::uint16_t, std::span<const std::uint8_t>) override {
    if (in_.empty()) return fail(ErrorKind::kGone, "scripted bootloader gone");
    if (in_.u8() % 16 == 0) return fail(ErrorKind::kRejected, "stalled");
    return done();
  }

  Expected<std::vector<std::uint8_t>> control_in(DfuRequest request, std::uint16_t,
                                                 std::uint16_t length) override {
    if (in_.empty()) return fail<std::vector<std::uint8_t>>(ErrorKind::kGone, "gone");
    const std::uint8_t how = in_.u8();
    if (how % 16 == 0) return fail<std::vector<std::uint8_t>>(ErrorKind::kRejected, "stalled");
    std::size_t n = 0;
    if (request == DfuRequest::kGetStatus)
      n = how % 8 == 1 ? in_.u8() % 8 : 6;  // mostly the 6 bytes GETSTATUS has
    else
      n = how % 4 == 1 ? in_.u16() % (length + 1u) : length;  // a short block now and then
    n = std::min<std::size_t>(n, length);                     // USB gives at most wLength bytes
    std::vector<std::uint8_t> out = in_.take(n);
    out.resize(n, 0);
    ++transfers_;
    return Expected<std::vector<std::uint8_t>>::success(std::move(out));
  }

  std::uint64_t transfers_ = 0;

 private:
  fuzz::Bytes& in_;
};

[[maybe_unused]] void fuzz_dfu(fuzz::Bytes& in) {
  ScriptedBootloader bootloader(in);
  std::uint64_t sleeps = 0;
  std::chrono::milliseconds slept{0};
  auto sleep = [&](std::chrono::milliseconds ms) {
    ++sleeps;
    slept += ms;
    FUZZ_CHECK(ms <= kMaxDfuPollSleep,
               "the flasher would sleep " + std::to_string(ms.count()) + " ms in one poll");
  };
  const auto status = dfu_get_status(bootloader);
  if (status.ok()) {
    FUZZ_CHECK(status.value().poll_timeout_ms <= 0xFFFFFF, "bwPollTimeout is 24 bits");
    FUZZ_CHECK(!dfu_status_text(static_cast<std::uint8_t>(status.value().status)).empty() &&
                   dfu_state_name(status.value().state) != nullptr,
               "status text");
  } else {
    FUZZ_CHECK(!status.error().message.empty(), "GETSTATUS failed without a message");
  }
  check_outcome(dfu_make_idle(bootloader), "make_idle");
  std::vector<std::uint8_t> image(1 + in.u16() % 3000, 0xA5);
  check_outcome(dfu_download(bootloader, image, nullptr, sleep), "download");
  const std::size_t length = in.u16() % 5000;
  const auto upload = dfu_upload(bootloader, length);
  if (upload.ok())
    FUZZ_CHECK(upload.value().size() <= length, "UPLOAD returned more than asked");
  else
    FUZZ_CHECK(!upload.error().message.empty(), "UPLOAD failed without a message");
  FUZZ_CHECK(sleeps <= bootloader.transfers_, "slept without polling");
  FUZZ_CHECK(slept <= 5 * (kMaxDfuBusyWait + kMaxDfuPollSleep),
             "the flasher waited " + std::to_string(slept.count()) + " ms on a busy device");
}

/// Reports one by one as the client's parsers take them: header, status, the
/// payload of every reply type and the exposure event.
[[maybe_unused]] void fuzz_reports(fuzz::Bytes& in) {
  while (!in.empty()) {
    const std::size_t length = in.u8() % (protocol::kReportSize + 8);
    const std::vector<std::uint8_t> report = in.take(length);
    const auto message = protocol::parse_message(report);
    const bool fits = report.size() >= protocol::kHeaderSize &&
                      report.size() <= protocol::kReportSize &&
                      report[2] <= report.size() - protocol::kHeaderSize;
    FUZZ_CHECK(message.ok() == fits, "parse_message disagrees with the report's lengths");
    if (!message.ok()) continue;
    const auto payload = message.value().payload;
    FUZZ_CHECK(payload.size() == report[2], "payload length");
    const auto command = static_cast<protocol::Command>(report[0]);
    const auto status = static_cast<protocol::Status>(report[3]);
    FUZZ_CHECK(!rejection_message(command, status).empty() && command_name(command) != nullptr,
               "texts");
    FUZZ_CHECK(!protocol_mismatch_message(report[0]).empty(), "mismatch text");
    auto decodes = [&](auto tag) {
      using T = decltype(tag);
      const auto decoded = protocol::decode_payload<T>(payload);
      FUZZ_CHECK(decoded.ok() == (payload.size() == sizeof(T)), "decode_payload length check");
    };
    decodes(protocol::InfoReply{});
    decodes(protocol::StatusReply{});
    decodes(protocol::SetCodeReply{});
    decodes(protocol::SelectCodeReply{});
    decodes(protocol::SelfTestReply{});
    decodes(protocol::SaveConfigReply{});
    decodes(protocol::ExposureEvent{});
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size > 16 * 1024) return 0;
  fuzz::Bytes in(data, size);
#ifdef FLUTTERSCAN_FUZZ_DEVICE_CLIENT
  fuzz_client(in);  // the device_client target: threads and reply waits, slow
#else
  if (in.u8() % 2 == 1)
    fuzz_dfu(in);
  else
    fuzz_reports(in);
#endif
  return 0;
}
