#include "device/controller_client.hpp"

#include <algorithm>
#include <cstring>

namespace flutterscan::device {

using protocol::Command;
using protocol::Status;

namespace {

constexpr auto kReaderPoll = std::chrono::milliseconds(20);

template <typename T>
std::span<const std::uint8_t> bytes_of(const T& value) {
  return {reinterpret_cast<const std::uint8_t*>(&value), sizeof(T)};
}

std::string milliseconds_text(std::chrono::microseconds us) {
  if (us.count() % 1000 == 0) return std::to_string(us.count() / 1000) + " ms";
  return std::to_string(us.count()) + " us";
}

}  // namespace

const char* command_name(Command command) {
  switch (command) {
    case Command::kGetInfo:
      return "GetInfo";
    case Command::kSetCode:
      return "SetCode";
    case Command::kSelectCode:
      return "SelectCode";
    case Command::kSetTiming:
      return "SetTiming";
    case Command::kSetMode:
      return "SetMode";
    case Command::kSetBrightness:
      return "SetBrightness";
    case Command::kArm:
      return "Arm";
    case Command::kDisarm:
      return "Disarm";
    case Command::kGetStatus:
      return "GetStatus";
    case Command::kSelfTest:
      return "SelfTest";
    case Command::kSaveConfig:
      return "SaveConfig";
    case Command::kEnterBootloader:
      return "EnterBootloader";
    case Command::kSetGuard:
      return "SetGuard";
    case Command::kExposureEvent:
      return "ExposureEvent";
  }
  return "command";
}

std::string protocol_mismatch_message(std::uint8_t firmware_major) {
  return "firmware speaks protocol " + std::to_string(firmware_major) +
         ", this flutterscan speaks " + std::to_string(protocol::kProtocolMajor) +
         ": run flutterscan flash";
}

std::string rejection_message(Command command, Status status) {
  return std::string(command_name(command)) +
         " refused by the controller: " + protocol::status_text(status) + " (status " +
         std::to_string(static_cast<int>(status)) + ")";
}

// ---------------------------------------------------------------------------
// Connection

ControllerClient::ControllerClient(TransportOpener opener, ClientOptions options)
    : opener_(std::move(opener)), options_(options) {}

Expected<std::unique_ptr<ControllerClient>> ControllerClient::connect(TransportOpener opener,
                                                                      ClientOptions options) {
  using Out = Expected<std::unique_ptr<ControllerClient>>;
  std::unique_ptr<ControllerClient> client(new ControllerClient(std::move(opener), options));
  auto opened = client->opener_();
  if (!opened.ok()) return fail<std::unique_ptr<ControllerClient>>(opened.error());
  std::shared_ptr<Transport> transport = std::move(opened.value());
  client->description_ = transport->description();
  const auto info = client->handshake(*transport);
  if (!info.ok()) {
    transport->close();
    return fail<std::unique_ptr<ControllerClient>>(info.error());
  }
  client->info_ = info.value();
  client->transport_ = transport;
  client->reader_ = std::thread([raw = client.get()] { raw->reader_loop(); });
  return Out::success(std::move(client));
}

ControllerClient::~ControllerClient() {
  std::shared_ptr<Transport> transport;
  {
    std::lock_guard lock(state_mutex_);
    stopping_ = true;
    transport = transport_;
  }
  state_changed_.notify_all();
  if (reader_.joinable()) reader_.join();
  if (transport) transport->close();
}

protocol::InfoReply ControllerClient::info() const {
  std::lock_guard lock(state_mutex_);
  return info_;
}

std::string ControllerClient::description() const {
  std::lock_guard lock(state_mutex_);
  return description_;
}

std::string ControllerClient::name() const {
  return description_;
}

bool ControllerClient::connected() const {
  std::lock_guard lock(state_mutex_);
  return transport_ != nullptr;
}

ClientStats ControllerClient::stats() const {
  std::lock_guard lock(state_mutex_);
  return stats_;
}

void ControllerClient::notice(const std::string& text) {
  std::function<void(const std::string&)> handler;
  {
    std::lock_guard lock(state_mutex_);
    handler = notice_handler_;
  }
  if (handler) handler(text);
}

void ControllerClient::set_notice_handler(std::function<void(const std::string&)> handler) {
  std::lock_guard lock(state_mutex_);
  notice_handler_ = std::move(handler);
}

void ControllerClient::set_event_handler(std::function<void(const EventNotice&)> handler) {
  std::lock_guard lock(state_mutex_);
  event_handler_ = std::move(handler);
}

std::optional<EventNotice> ControllerClient::next_event(std::chrono::milliseconds timeout) {
  std::unique_lock lock(state_mutex_);
  state_changed_.wait_for(lock, timeout, [&] { return !events_.empty() || stopping_; });
  if (events_.empty()) return std::nullopt;
  EventNotice notice = events_.front();
  events_.pop_front();
  return notice;
}

// ---------------------------------------------------------------------------
// Exchanging reports

Expected<std::optional<Report>> ControllerClient::attempt_direct(Transport& transport,
                                                                 const Report& request) {
  using Out = Expected<std::optional<Report>>;
  const auto written = transport.write_report(request);
  if (!written.ok()) return fail<std::optional<Report>>(written.error());
  const auto deadline = std::chrono::steady_clock::now() + options_.reply_timeout;
  for (;;) {
    const auto left = std::chrono::duration_cast<std::chrono::microseconds>(
        deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) return Out::success(std::nullopt);
    // Transports wait in whole milliseconds: round up, so that a wait under 1 ms still reads.
    auto read = transport.read_report(std::chrono::ceil<std::chrono::milliseconds>(left));
    if (!read.ok()) return fail<std::optional<Report>>(read.error());
    if (!read.value()) continue;
    const Report& report = *read.value();
    if (report[0] == static_cast<std::uint8_t>(Command::kExposureEvent)) {
      handle_event(report);
    } else if (report[0] == request[0] && report[1] == request[1]) {
      return Out::success(report);
    } else {
      std::lock_guard lock(state_mutex_);
      ++stats_.stale_replies;
    }
  }
}

std::chrono::microseconds ControllerClient::reply_timeout_for(Command command) const {
  if (command == Command::kSaveConfig)
    return std::max(options_.reply_timeout, options_.save_config_timeout);
  return options_.reply_timeout;
}

Expected<std::optional<Report>> ControllerClient::attempt_locked(std::unique_lock<std::mutex>& lock,
                                                                 const Report& request,
                                                                 bool* not_sent,
                                                                 std::chrono::microseconds timeout) {
  using Out = Expected<std::optional<Report>>;
  const std::shared_ptr<Transport> transport = transport_;
  waiting_ = true;
  waiting_command_ = request[0];
  waiting_sequence_ = request[1];
  reply_.reset();
  reply_link_lost_ = false;
  lock.unlock();
  const auto written = transport->write_report(request);
  lock.lock();
  if (!written.ok()) {
    waiting_ = false;
    if (not_sent) *not_sent = true;
    lock.unlock();
    mark_gone(transport, written.error().message);
    lock.lock();
    return fail<std::optional<Report>>(ErrorKind::kGone, written.error().message);
  }
  state_changed_.wait_for(lock, timeout,
                          [&] { return reply_.has_value() || reply_link_lost_ || stopping_; });
  waiting_ = false;
  if (reply_) return Out::success(*reply_);
  if (reply_link_lost_ || stopping_)
    return fail<std::optional<Report>>(ErrorKind::kGone,
                                       name() + ": link lost (" + gone_reason_ + ")");
  return Out::success(std::nullopt);
}

Expected<Report> ControllerClient::transact(Command command,
                                            std::span<const std::uint8_t> payload) {
  std::lock_guard command_lock(command_mutex_);
  const int attempts = 1 + std::max(0, options_.retries);
  int unsent = 0;  // requests that never left because the link had just gone
  for (int attempt = 0; attempt < attempts; ++attempt) {
    std::unique_lock lock(state_mutex_);
    if (!transport_) {
      if (bootloader_requested_ || !options_.reconnect || stopping_)
        return fail<Report>(ErrorKind::kGone, name() + " is gone (" + gone_reason_ + ")");
      state_changed_.wait_for(lock, options_.reconnect_wait,
                              [&] { return transport_ != nullptr || stopping_; });
      if (!transport_)
        return fail<Report>(ErrorKind::kGone, name() + " is gone (" + gone_reason_ +
                                                  ") and did not come back within " +
                                                  milliseconds_text(options_.reconnect_wait));
    }
    Report request{};
    const std::uint8_t sequence = next_sequence_++;
    if (protocol::encode_raw(static_cast<std::uint8_t>(command), sequence, Status::kOk, payload,
                             request) != protocol::kReportSize)
      return fail<Report>(ErrorKind::kBadInput,
                          std::string(command_name(command)) + ": payload of " +
                              std::to_string(payload.size()) + " bytes does not fit a report");
    if (attempt == 0 && unsent == 0)
      ++stats_.commands;
    else if (attempt > 0)
      ++stats_.retries;
    bool not_sent = false;
    auto reply = attempt_locked(lock, request, &not_sent, reply_timeout_for(command));
    if (!reply.ok() && not_sent && options_.reconnect && !bootloader_requested_ && ++unsent < 3) {
      --attempt;  // nothing was sent: wait for the controller to come back, then send
      continue;
    }
    if (!reply.ok()) return fail<Report>(reply.error());
    if (reply.value()) return Expected<Report>::success(*reply.value());
  }
  return fail<Report>(ErrorKind::kTimeout, "no reply from " + name() + " to " +
                                               command_name(command) + " within " +
                                               milliseconds_text(reply_timeout_for(command)) + " (" +
                                               std::to_string(attempts) + " attempts)");
}

Expected<Report> ControllerClient::exchange_raw(std::span<const std::uint8_t> request) {
  if (request.size() < protocol::kHeaderSize)
    return fail<Report>(ErrorKind::kBadInput, "a request needs at least a 4-byte header");
  // The sequence byte is the client's; everything else goes out as given.
  std::lock_guard command_lock(command_mutex_);
  std::unique_lock lock(state_mutex_);
  if (!transport_)
    return fail<Report>(ErrorKind::kGone, name() + " is gone (" + gone_reason_ + ")");
  Report report{};
  std::copy_n(request.begin(), std::min(request.size(), report.size()), report.begin());
  report[1] = next_sequence_++;
  ++stats_.commands;
  auto reply = attempt_locked(lock, report, nullptr, options_.reply_timeout);
  if (!reply.ok()) return fail<Report>(reply.error());
  if (!reply.value())
    return fail<Report>(ErrorKind::kTimeout, "no reply from " + name() + " within " +
                                                 milliseconds_text(options_.reply_timeout));
  return Expected<Report>::success(*reply.value());
}

namespace {

/// The reply's payload after checking its status: kRejected with the status text.
Expected<std::span<const std::uint8_t>> accepted_payload(Command command, const Report& reply) {
  using Out = Expected<std::span<const std::uint8_t>>;
  const auto message = protocol::parse_message(reply);
  if (!message.ok())
    return fail<std::span<const std::uint8_t>>(
        ErrorKind::kBadReply, std::string("malformed reply to ") + command_name(command) +
                                  " (payload length " + std::to_string(reply[2]) + ")");
  const auto status = static_cast<Status>(message.value().header.status);
  if (status != Status::kOk)
    return fail<std::span<const std::uint8_t>>(ErrorKind::kRejected,
                                               rejection_message(command, status), status);
  return Out::success(message.value().payload);
}

}  // namespace

template <typename T>
Expected<T> ControllerClient::command_with_reply(Command command,
                                                 std::span<const std::uint8_t> payload) {
  const auto reply = transact(command, payload);
  if (!reply.ok()) return fail<T>(reply.error());
  // The payload views `reply`'s report: decode while it is alive.
  const Report& report = reply.value();
  const auto accepted = accepted_payload(command, report);
  if (!accepted.ok()) return fail<T>(accepted.error());
  const auto decoded = protocol::decode_payload<T>(accepted.value());
  if (!decoded.ok())
    return fail<T>(ErrorKind::kBadReply, std::string("reply to ") + command_name(command) +
                                             " has " + std::to_string(accepted.value().size()) +
                                             " payload bytes, expected " +
                                             std::to_string(sizeof(T)));
  return Expected<T>::success(decoded.value());
}

Expected<Done> ControllerClient::command_status_only(Command command,
                                                     std::span<const std::uint8_t> payload) {
  const auto reply = transact(command, payload);
  if (!reply.ok()) return fail(reply.error());
  const auto accepted = accepted_payload(command, reply.value());
  if (!accepted.ok()) return fail(accepted.error());
  return done();
}

Expected<protocol::InfoReply> ControllerClient::handshake(Transport& transport) {
  using Out = Expected<protocol::InfoReply>;
  const int attempts = 1 + std::max(0, options_.retries);
  for (int attempt = 0; attempt < attempts; ++attempt) {
    Report request{};
    {
      std::lock_guard lock(state_mutex_);
      protocol::encode_request(Command::kGetInfo, next_sequence_++, request);
    }
    const auto reply = attempt_direct(transport, request);
    if (!reply.ok()) return fail<protocol::InfoReply>(reply.error());
    if (!reply.value()) continue;
    const Report report = *reply.value();
    const auto accepted = accepted_payload(Command::kGetInfo, report);
    if (!accepted.ok()) return fail<protocol::InfoReply>(accepted.error());
    // The major sits in the first payload byte whatever the rest looks like.
    if (!accepted.value().empty() && accepted.value()[0] != protocol::kProtocolMajor)
      return fail<protocol::InfoReply>(ErrorKind::kProtocolMismatch,
                                       protocol_mismatch_message(accepted.value()[0]));
    const auto info = protocol::decode_payload<protocol::InfoReply>(accepted.value());
    if (!info.ok())
      return fail<protocol::InfoReply>(
          ErrorKind::kBadReply, "GetInfo reply of " + std::to_string(accepted.value().size()) +
                                    " bytes from " + transport.description());
    return Out::success(info.value());
  }
  return fail<protocol::InfoReply>(
      ErrorKind::kTimeout, "no reply from " + transport.description() + " to GetInfo within " +
                               milliseconds_text(options_.reply_timeout) + " (" +
                               std::to_string(attempts) + " attempts)");
}

// ---------------------------------------------------------------------------
// Reader thread

void ControllerClient::reader_loop() {
  for (;;) {
    std::shared_ptr<Transport> transport;
    bool may_reconnect = false;
    {
      std::unique_lock lock(state_mutex_);
      if (stopping_) return;
      transport = transport_;
      may_reconnect = options_.reconnect && !bootloader_requested_;
      if (!transport && !may_reconnect) {
        state_changed_.wait(lock, [&] { return stopping_; });
        return;
      }
    }
    if (!transport) {
      try_reconnect();
      continue;
    }
    auto read = transport->read_report(kReaderPoll);
    if (!read.ok()) {
      mark_gone(transport, read.error().message);
      continue;
    }
    if (read.value()) handle_report(*read.value());
  }
}

void ControllerClient::handle_report(const Report& report) {
  if (report[0] == static_cast<std::uint8_t>(Command::kExposureEvent)) {
    handle_event(report);
    return;
  }
  std::lock_guard lock(state_mutex_);
  if (waiting_ && !reply_ && report[0] == waiting_command_ && report[1] == waiting_sequence_) {
    reply_ = report;
    state_changed_.notify_all();
  } else {
    ++stats_.stale_replies;
  }
}

void ControllerClient::handle_event(const Report& report) {
  const auto message = protocol::parse_message(report);
  std::optional<protocol::ExposureEvent> event;
  if (message.ok()) {
    const auto decoded = protocol::decode_payload<protocol::ExposureEvent>(message.value().payload);
    if (decoded.ok()) event = decoded.value();
  }
  std::function<void(const EventNotice&)> handler;
  EventNotice notice;
  {
    std::lock_guard lock(state_mutex_);
    if (!event) {
      ++stats_.bad_reports;
      return;
    }
    notice.event = *event;
    const std::uint32_t counter = event->frame_counter;
    if (last_frame_counter_) {
      const std::uint32_t last = *last_frame_counter_;
      if (counter > last + 1)
        notice.frames_missing_before = counter - last - 1;
      else if (counter <= last && counter > 1)  // a new Arm whose first events were lost
        notice.frames_missing_before = counter - 1;
    }
    last_frame_counter_ = counter;
    ++stats_.events;
    stats_.frames_missing += notice.frames_missing_before;
    handler = event_handler_;
    if (!handler) {
      if (events_.size() >= options_.event_queue_limit) {
        events_.pop_front();
        ++stats_.events_overflowed;
      }
      events_.push_back(notice);
      state_changed_.notify_all();
    }
  }
  if (handler) handler(notice);
}

void ControllerClient::mark_gone(const std::shared_ptr<Transport>& transport,
                                 const std::string& why) {
  bool expected_reset = false;
  {
    std::lock_guard lock(state_mutex_);
    if (transport_ != transport) return;  // already handled
    transport_.reset();
    gone_reason_ = why;
    if (waiting_) reply_link_lost_ = true;
    expected_reset = bootloader_requested_;
  }
  state_changed_.notify_all();
  transport->close();
  if (!expected_reset)
    notice(name() + ": link lost (" + why + ")" +
           (options_.reconnect ? "; waiting for it to come back" : ""));
}

void ControllerClient::try_reconnect() {
  {
    std::unique_lock lock(state_mutex_);
    if (state_changed_.wait_for(lock, options_.reconnect_interval, [&] { return stopping_; }))
      return;
  }
  auto opened = opener_();
  if (!opened.ok()) return;
  std::shared_ptr<Transport> transport = std::move(opened.value());
  const auto info = handshake(*transport);
  if (!info.ok()) {
    transport->close();
    if (info.error().kind == ErrorKind::kProtocolMismatch) {
      std::lock_guard lock(state_mutex_);
      if (gone_reason_ == info.error().message) return;
      gone_reason_ = info.error().message;
    } else {
      return;
    }
    notice(name() + " is back but refused: " + info.error().message);
    return;
  }
  const auto restored = restore_session(*transport);
  if (!restored.ok()) {
    transport->close();
    notice(name() + " is back but restoring its settings failed: " + restored.error().message);
    return;
  }
  {
    std::lock_guard lock(state_mutex_);
    info_ = info.value();
    transport_ = transport;
    last_frame_counter_.reset();
    ++stats_.reconnects;
  }
  state_changed_.notify_all();
  notice(name() + " is back: " + restored.value());
}

Expected<std::string> ControllerClient::restore_session(Transport& transport) {
  SessionState session;
  {
    std::lock_guard lock(state_mutex_);
    session = session_;
  }
  std::vector<std::string> restored;
  // One request on the new link, checked; `what` names it in the message.
  auto send = [&](Command command, std::span<const std::uint8_t> payload) -> Expected<Done> {
    const int attempts = 1 + std::max(0, options_.retries);
    for (int attempt = 0; attempt < attempts; ++attempt) {
      Report request{};
      {
        std::lock_guard lock(state_mutex_);
        protocol::encode_raw(static_cast<std::uint8_t>(command), next_sequence_++, Status::kOk,
                             payload, request);
      }
      const auto reply = attempt_direct(transport, request);
      if (!reply.ok()) return fail(reply.error());
      if (!reply.value()) continue;
      const Report report = *reply.value();
      const auto accepted = accepted_payload(command, report);
      if (!accepted.ok()) return fail(accepted.error());
      return done();
    }
    return fail(ErrorKind::kTimeout,
                std::string("no reply to ") + command_name(command) + " while restoring");
  };
  if (session.guard) {
    if (auto r = send(Command::kSetGuard, bytes_of(*session.guard)); !r.ok())
      return fail<std::string>(r.error());
    restored.push_back("guard");
  }
  if (session.timing) {
    if (auto r = send(Command::kSetTiming, bytes_of(*session.timing)); !r.ok())
      return fail<std::string>(r.error());
    restored.push_back("timing");
  }
  if (session.mode) {
    if (auto r = send(Command::kSetMode, bytes_of(*session.mode)); !r.ok())
      return fail<std::string>(r.error());
    restored.push_back("mode");
  }
  if (session.brightness) {
    if (auto r = send(Command::kSetBrightness, bytes_of(*session.brightness)); !r.ok())
      return fail<std::string>(r.error());
    restored.push_back("brightness");
  }
  for (const auto& [id, entry] : session.codes) {
    for (const auto& chunk : code_chunks(id, entry.first, entry.second))
      if (auto r = send(Command::kSetCode, bytes_of(chunk)); !r.ok())
        return fail<std::string>(r.error());
    restored.push_back("code " + std::to_string(id));
  }
  if (session.selected_code) {
    const protocol::SelectCodeRequest select{*session.selected_code, {}};
    if (auto r = send(Command::kSelectCode, bytes_of(select)); !r.ok())
      return fail<std::string>(r.error());
    restored.push_back("selected code " + std::to_string(*session.selected_code));
  }
  if (session.armed) {
    if (auto r = send(Command::kArm, {}); !r.ok()) return fail<std::string>(r.error());
    restored.push_back("armed again");
  }
  std::string text;
  if (restored.empty()) {
    text = "nothing to restore (no settings were sent in this session)";
  } else {
    text = "re-sent ";
    for (std::size_t i = 0; i < restored.size(); ++i)
      text += (i == 0 ? "" : i + 1 == restored.size() ? " and " : ", ") + restored[i];
  }
  return Expected<std::string>::success(text);
}

// ---------------------------------------------------------------------------
// Commands

std::vector<protocol::SetCodeRequest> code_chunks(std::uint8_t code_id, const LedCode& code,
                                                  bool one_of_n) {
  std::vector<protocol::SetCodeRequest> chunks;
  for (int first = 0; first < code.length();
       first += static_cast<int>(protocol::kSlotsPerCodeChunk)) {
    protocol::SetCodeRequest r{};
    r.code_id = code_id;
    r.led_count = static_cast<std::uint8_t>(code.leds());
    r.total_slots = static_cast<std::uint16_t>(code.length());
    r.first_slot = static_cast<std::uint16_t>(first);
    const int count =
        std::min<int>(code.length() - first, static_cast<int>(protocol::kSlotsPerCodeChunk));
    r.slot_count = static_cast<std::uint8_t>(count);
    r.flags = one_of_n ? protocol::kCodeFlagOneOfN : 0;
    for (int i = 0; i < count; ++i) r.masks[static_cast<std::size_t>(i)] = code.mask(first + i);
    chunks.push_back(r);
  }
  return chunks;
}

Expected<protocol::SetCodeReply> ControllerClient::set_code(std::uint8_t code_id,
                                                            const LedCode& code, bool one_of_n) {
  std::lock_guard command_lock(command_mutex_);
  const auto chunks = code_chunks(code_id, code, one_of_n);
  // A chunk whose first reply was lost and that was applied anyway makes its
  // resend OutOfOrder: then the whole upload starts again once.
  for (int pass = 0; pass < 2; ++pass) {
    const std::uint64_t retries_before = stats().retries;
    protocol::SetCodeReply last{};
    bool restart = false;
    for (const auto& chunk : chunks) {
      auto reply = command_with_reply<protocol::SetCodeReply>(Command::kSetCode, bytes_of(chunk));
      if (!reply.ok()) {
        if (pass == 0 && reply.error().status == Status::kOutOfOrder &&
            stats().retries != retries_before) {
          restart = true;
          break;
        }
        return reply;
      }
      last = reply.value();
    }
    if (restart) continue;
    if (!last.complete)
      return fail<protocol::SetCodeReply>(
          ErrorKind::kBadReply, "the controller did not report code " + std::to_string(code_id) +
                                    " complete after " + std::to_string(last.slots_received) +
                                    " slots");
    std::lock_guard lock(state_mutex_);
    session_.codes.insert_or_assign(code_id, std::make_pair(code, one_of_n));
    return Expected<protocol::SetCodeReply>::success(last);
  }
  return fail<protocol::SetCodeReply>(ErrorKind::kTimeout, "code upload kept getting out of order");
}

Expected<protocol::SelectCodeReply> ControllerClient::select_code(std::uint8_t code_id) {
  const protocol::SelectCodeRequest request{code_id, {}};
  auto reply =
      command_with_reply<protocol::SelectCodeReply>(Command::kSelectCode, bytes_of(request));
  if (reply.ok()) {
    std::lock_guard lock(state_mutex_);
    session_.selected_code = code_id;
  }
  return reply;
}

Expected<Done> ControllerClient::set_timing(const protocol::SetTimingRequest& request) {
  auto result = command_status_only(Command::kSetTiming, bytes_of(request));
  if (result.ok()) {
    std::lock_guard lock(state_mutex_);
    session_.timing = request;
  }
  return result;
}

Expected<Done> ControllerClient::set_mode(protocol::SyncMode mode, bool strobe_active_low) {
  const protocol::SetModeRequest request{
      static_cast<std::uint8_t>(mode), static_cast<std::uint8_t>(strobe_active_low ? 1 : 0), {}};
  auto result = command_status_only(Command::kSetMode, bytes_of(request));
  if (result.ok()) {
    std::lock_guard lock(state_mutex_);
    session_.mode = request;
  }
  return result;
}

Expected<Done> ControllerClient::set_brightness(const protocol::SetBrightnessRequest& request) {
  auto result = command_status_only(Command::kSetBrightness, bytes_of(request));
  if (result.ok()) {
    std::lock_guard lock(state_mutex_);
    session_.brightness = request;
  }
  return result;
}

Expected<Done> ControllerClient::set_guard(const protocol::SetGuardRequest& request) {
  auto result = command_status_only(Command::kSetGuard, bytes_of(request));
  if (result.ok()) {
    std::lock_guard lock(state_mutex_);
    session_.guard = request;
  }
  return result;
}

Expected<Done> ControllerClient::arm() {
  std::lock_guard command_lock(command_mutex_);
  const std::uint64_t retries_before = stats().retries;
  auto result = command_status_only(Command::kArm, {});
  if (!result.ok() && result.error().status == Status::kBadState &&
      stats().retries != retries_before) {
    // The first Arm was applied but its reply lost: armed is what was asked for.
    const auto now = status();
    if (now.ok() &&
        (now.value().state == static_cast<std::uint8_t>(protocol::ControllerState::kArmed) ||
         now.value().state == static_cast<std::uint8_t>(protocol::ControllerState::kExposing)))
      result = done();
  }
  if (result.ok()) {
    std::lock_guard lock(state_mutex_);
    session_.armed = true;
    last_frame_counter_ = 0;
  }
  return result;
}

Expected<Done> ControllerClient::disarm() {
  auto result = command_status_only(Command::kDisarm, {});
  if (result.ok()) {
    std::lock_guard lock(state_mutex_);
    session_.armed = false;
  }
  return result;
}

Expected<protocol::StatusReply> ControllerClient::status() {
  return command_with_reply<protocol::StatusReply>(Command::kGetStatus, {});
}

Expected<protocol::SelfTestReply> ControllerClient::self_test(std::uint32_t step_time_us) {
  const protocol::SelfTestRequest request{step_time_us};
  return command_with_reply<protocol::SelfTestReply>(Command::kSelfTest, bytes_of(request));
}

Expected<protocol::SaveConfigReply> ControllerClient::save_config() {
  return command_with_reply<protocol::SaveConfigReply>(Command::kSaveConfig, {});
}

Expected<Done> ControllerClient::enter_bootloader() {
  {
    std::lock_guard lock(state_mutex_);
    bootloader_requested_ = true;
  }
  const protocol::EnterBootloaderRequest request{protocol::kEnterBootloaderMagic};
  auto result = command_status_only(Command::kEnterBootloader, bytes_of(request));
  // The controller may reset before its reply is read: the link going away is success.
  if (!result.ok() && result.error().kind == ErrorKind::kGone) return done();
  if (!result.ok()) {
    std::lock_guard lock(state_mutex_);
    bootloader_requested_ = false;
  }
  return result;
}

}  // namespace flutterscan::device
