#pragma once
// The host's side of the protocol: one connected controller, reached through a
// Transport. GetInfo comes first and a protocol major mismatch is refused;
// every command has a timeout and bounded retries, replies are matched by
// command and sequence number (stale ones are discarded and counted), error
// statuses become messages. A reader thread takes every IN report: replies go
// to the waiting command, exposure events to a handler or a queue, with gaps in
// the frame counter reported. After an unplug the client re-opens the same
// controller when it comes back, restores the codes and settings it set in
// this session (and re-arms if it was armed), and says so.

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "device/device_error.hpp"
#include "device/transport.hpp"
#include "flutterscan/common/led_code.hpp"
#include "flutterscan/common/protocol.hpp"

namespace flutterscan::device {

/// \brief Timeouts and retries of a client.
struct ClientOptions {
  /// Wait for one reply (microseconds so that a test or fuzz harness can wait less than a
  /// millisecond; a `std::chrono::milliseconds` assigns as usual).
  std::chrono::microseconds reply_timeout{std::chrono::milliseconds(500)};
  /// Extra attempts after a timeout (so 1 + retries in all).
  int retries = 2;
  /// Wait for SaveConfig's reply (at least reply_timeout): the controller erases
  /// a flash sector first, up to 2 s for the 128 KiB sector 11 (STM32F405
  /// datasheet, t_ERASE128KB at x32), with interrupts masked, so it cannot answer sooner.
  std::chrono::microseconds save_config_timeout{std::chrono::milliseconds(4000)};
  /// After an unplug: how long a command waits for the controller to come back.
  std::chrono::milliseconds reconnect_wait{3000};
  /// Between attempts to re-open an unplugged controller.
  std::chrono::milliseconds reconnect_interval{100};
  /// Re-open the controller after an unplug.
  bool reconnect = true;
  /// Events kept for next_event() when no handler is set (older ones are dropped and counted).
  std::size_t event_queue_limit = 4096;
};

/// \brief One exposure event as the host saw it.
struct EventNotice {
  protocol::ExposureEvent event{};
  /// Exposures whose events never arrived just before this one (frame counter gap), 0 if none.
  std::uint32_t frames_missing_before = 0;
};

/// \brief Counters of the link (for messages and tests).
struct ClientStats {
  std::uint64_t commands = 0;           ///< commands sent (first attempts)
  std::uint64_t retries = 0;            ///< re-sends after a timeout
  std::uint64_t stale_replies = 0;      ///< replies that matched no waiting command
  std::uint64_t events = 0;             ///< exposure events received
  std::uint64_t frames_missing = 0;     ///< exposures whose events never arrived (gaps)
  std::uint64_t events_overflowed = 0;  ///< events dropped from a full next_event() queue
  std::uint64_t reconnects = 0;         ///< times the controller came back and was restored
  std::uint64_t bad_reports = 0;        ///< IN reports that did not parse
};

/// \brief A connected controller. Thread-safe: commands may come from several threads.
class ControllerClient {
 public:
  /// \brief Opens the link with `opener`, sends GetInfo and checks the protocol major.
  /// The opener is kept for re-opening after an unplug.
  static Expected<std::unique_ptr<ControllerClient>> connect(TransportOpener opener,
                                                             ClientOptions options = {});
  ~ControllerClient();
  ControllerClient(const ControllerClient&) = delete;
  ControllerClient& operator=(const ControllerClient&) = delete;

  /// \brief The GetInfo reply of the (last) connection.
  protocol::InfoReply info() const;
  /// \brief The link's description (e.g. the hidraw path).
  std::string description() const;

  // Commands ------------------------------------------------------------------
  /// \brief Uploads `code` under `code_id` in chunks (one-of-N checked by the
  /// controller when `one_of_n`).
  Expected<protocol::SetCodeReply> set_code(std::uint8_t code_id, const LedCode& code,
                                            bool one_of_n);
  Expected<protocol::SelectCodeReply> select_code(std::uint8_t code_id);
  Expected<Done> set_timing(const protocol::SetTimingRequest& request);
  Expected<Done> set_mode(protocol::SyncMode mode, bool strobe_active_low);
  Expected<Done> set_brightness(const protocol::SetBrightnessRequest& request);
  Expected<Done> set_guard(const protocol::SetGuardRequest& request);
  Expected<Done> arm();
  Expected<Done> disarm();
  Expected<protocol::StatusReply> status();
  Expected<protocol::SelfTestReply> self_test(std::uint32_t step_time_us);
  Expected<protocol::SaveConfigReply> save_config();
  /// \brief Asks the application to reset into its DFU bootloader; the link is then gone
  /// (no reconnect is attempted afterwards).
  Expected<Done> enter_bootloader();
  /// \brief Sends a raw request report and returns the raw reply (tests, diagnostics).
  Expected<Report> exchange_raw(std::span<const std::uint8_t> request);

  // Events and notices --------------------------------------------------------
  /// \brief Events go to `handler` (called on the reader thread) instead of the queue.
  void set_event_handler(std::function<void(const EventNotice&)> handler);
  /// \brief The oldest queued event, waiting at most `timeout`.
  std::optional<EventNotice> next_event(std::chrono::milliseconds timeout);
  /// \brief Messages about the link (unplugged, back and restored) go to `handler`.
  void set_notice_handler(std::function<void(const std::string&)> handler);

  ClientStats stats() const;
  /// \brief Whether the link is up now.
  bool connected() const;

 private:
  /// What the client set in this session, restored after a reconnect.
  struct SessionState {
    std::map<std::uint8_t, std::pair<LedCode, bool>> codes;  ///< id -> code, one-of-N
    std::optional<std::uint8_t> selected_code;
    std::optional<protocol::SetTimingRequest> timing;
    std::optional<protocol::SetModeRequest> mode;
    std::optional<protocol::SetBrightnessRequest> brightness;
    std::optional<protocol::SetGuardRequest> guard;
    bool armed = false;
  };

  ControllerClient(TransportOpener opener, ClientOptions options);

  /// Sends `request` (command and payload already encoded, sequence filled in here)
  /// and waits for its reply, with retries.
  Expected<Report> transact(protocol::Command command, std::span<const std::uint8_t> payload);
  /// How long to wait for the reply to `command`.
  std::chrono::microseconds reply_timeout_for(protocol::Command command) const;
  /// One attempt through the reader thread, waiting `timeout`; `*not_sent` true
  /// if the write failed.
  Expected<std::optional<Report>> attempt_locked(std::unique_lock<std::mutex>& state_lock,
                                                 const Report& request, bool* not_sent,
                                                 std::chrono::microseconds timeout);
  /// One attempt reading the transport directly (connect and restore, no reader thread).
  Expected<std::optional<Report>> attempt_direct(Transport& transport, const Report& request);
  /// transact + status check + payload decoding.
  template <typename T>
  Expected<T> command_with_reply(protocol::Command command, std::span<const std::uint8_t> payload);
  Expected<Done> command_status_only(protocol::Command command,
                                     std::span<const std::uint8_t> payload);

  /// GetInfo on a freshly opened transport (direct reads); checks the major.
  Expected<protocol::InfoReply> handshake(Transport& transport);
  /// After a reconnect: re-sends the session state; a description of what was restored.
  Expected<std::string> restore_session(Transport& transport);

  void reader_loop();
  void handle_report(const Report& report);
  void handle_event(const Report& report);
  void mark_gone(const std::shared_ptr<Transport>& transport, const std::string& why);
  void try_reconnect();
  void notice(const std::string& text);
  std::string name() const;

  TransportOpener opener_;
  ClientOptions options_;

  mutable std::mutex state_mutex_;
  std::condition_variable state_changed_;
  std::shared_ptr<Transport> transport_;  ///< null while disconnected
  bool stopping_ = false;
  bool bootloader_requested_ = false;
  std::string gone_reason_;
  protocol::InfoReply info_{};
  std::string description_;
  std::uint8_t next_sequence_ = 1;
  // The command waiting for its reply.
  bool waiting_ = false;
  std::uint8_t waiting_command_ = 0;
  std::uint8_t waiting_sequence_ = 0;
  std::optional<Report> reply_;
  bool reply_link_lost_ = false;
  // Events.
  std::function<void(const EventNotice&)> event_handler_;
  std::function<void(const std::string&)> notice_handler_;
  std::deque<EventNotice> events_;
  std::optional<std::uint32_t> last_frame_counter_;
  ClientStats stats_;

  std::recursive_mutex command_mutex_;  ///< one command (or code upload) at a time
  SessionState session_;                ///< guarded by command_mutex_
  std::thread reader_;
};

/// \brief SetCode requests uploading `code` under `code_id` (52 slots per chunk).
std::vector<protocol::SetCodeRequest> code_chunks(std::uint8_t code_id, const LedCode& code,
                                                  bool one_of_n);
/// \brief "firmware speaks protocol X, this flutterscan speaks Y: run flutterscan flash".
std::string protocol_mismatch_message(std::uint8_t firmware_major);
/// \brief "SetTiming refused: argument out of range" style text for a status.
std::string rejection_message(protocol::Command command, protocol::Status status);
/// \brief The command's name as in docs/protocol.md ("GetInfo", "SetCode", ...).
const char* command_name(protocol::Command command);

}  // namespace flutterscan::device
