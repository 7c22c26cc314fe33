// The controller client against the firmware core through InProcessTransport:
// every command's happy path and a rejection, event gaps, timeouts, stale
// replies, reconnect and restore.
#include "device/controller_client.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <mutex>
#include <string_view>
#include <thread>
#include <vector>

#include "device/in_process_transport.hpp"
#include "device/virtual_controller.hpp"

namespace flutterscan::device {
namespace {

namespace proto = flutterscan::protocol;
using std::chrono::milliseconds;

constexpr std::string_view kCode = "2212441414112412441224111241244244242212442211444144";

LedCode code_of(std::string_view digits, int leds = 3) {
  const auto code = LedCode::parse(digits, leds);
  EXPECT_TRUE(code.ok());
  return code.value();
}

ClientOptions fast_options() {
  ClientOptions options;
  options.reply_timeout = milliseconds(100);
  options.retries = 1;
  options.reconnect_wait = milliseconds(2000);
  options.reconnect_interval = milliseconds(5);
  return options;
}

/// Collects notices from the client's threads.
struct Notices {
  std::mutex mutex;
  std::vector<std::string> lines;
  void add(const std::string& line) {
    std::lock_guard lock(mutex);
    lines.push_back(line);
  }
  bool contains(std::string_view text) {
    std::lock_guard lock(mutex);
    for (const auto& line : lines)
      if (line.find(text) != std::string::npos) return true;
    return false;
  }
};

class ClientTest : public ::testing::Test {
 protected:
  void SetUp() override { connect_client(); }

  void connect_client(ClientOptions options = fast_options()) {
    auto connected = ControllerClient::connect(in_process_opener(vc), options);
    ASSERT_TRUE(connected.ok()) << connected.error().message;
    client = std::move(connected.value());
    client->set_notice_handler([this](const std::string& line) { notices.add(line); });
  }

  /// Code 0 uploaded and selected, 100 us slots, armed (slave mode).
  void arm_with_code() {
    ASSERT_TRUE(client->set_code(0, code_of(kCode), true).ok());
    ASSERT_TRUE(client->select_code(0).ok());
    ASSERT_TRUE(client->set_timing({100, 0, 0, {}}).ok());
    ASSERT_TRUE(client->arm().ok());
  }

  std::shared_ptr<VirtualController> vc = std::make_shared<VirtualController>();
  std::unique_ptr<ControllerClient> client;
  Notices notices;
};

template <typename T>
void expect_rejected(const Expected<T>& result, proto::Status status, std::string_view text) {
  ASSERT_FALSE(result.ok());
  EXPECT_EQ(result.error().kind, ErrorKind::kRejected);
  EXPECT_EQ(result.error().status, status);
  EXPECT_NE(result.error().message.find(text), std::string::npos) << result.error().message;
}

// --- connection -------------------------------------------------------------

TEST_F(ClientTest, ConnectReadsInfo) {
  const auto info = client->info();
  EXPECT_EQ(info.protocol_major, proto::kProtocolMajor);
  EXPECT_EQ(info.led_count, 3);
  EXPECT_EQ(info.board_id, vc->board().board_id);
  EXPECT_NE(client->description().find(vc->serial_number()), std::string::npos);
}

TEST(Client, ProtocolMajorMismatchIsRefusedWithTheActionableMessage) {
  VirtualControllerOptions options;
  options.reported_protocol_major = proto::kProtocolMajor + 1;
  auto vc = std::make_shared<VirtualController>(options);
  const auto connected = ControllerClient::connect(in_process_opener(vc), fast_options());
  ASSERT_FALSE(connected.ok());
  EXPECT_EQ(connected.error().kind, ErrorKind::kProtocolMismatch);
  EXPECT_EQ(connected.error().message,
            "firmware speaks protocol " + std::to_string(proto::kProtocolMajor + 1) +
                ", this flutterscan speaks " + std::to_string(proto::kProtocolMajor) +
                ": run flutterscan flash");
}

TEST(Client, ConnectToAnUnpluggedControllerFails) {
  auto vc = std::make_shared<VirtualController>();
  vc->unplug();
  const auto connected = ControllerClient::connect(in_process_opener(vc), fast_options());
  ASSERT_FALSE(connected.ok());
  EXPECT_EQ(connected.error().kind, ErrorKind::kNotFound);
}

// --- every command: happy path and a rejection -------------------------------

TEST_F(ClientTest, SetCode) {
  const auto stored = client->set_code(2, code_of(kCode), true);
  ASSERT_TRUE(stored.ok()) << stored.error().message;
  EXPECT_EQ(stored.value().complete, 1);
  EXPECT_EQ(stored.value().slots_received, kCode.size());
  // 120 slots: three chunks.
  std::string longer;
  while (longer.size() < 120) longer += "124";
  ASSERT_TRUE(client->set_code(3, code_of(longer.substr(0, 120)), true).ok());
  EXPECT_EQ(client->status().value().codes_stored, 0b1100);
  expect_rejected(client->set_code(9, code_of(kCode), true), proto::Status::kOutOfRange,
                  "SetCode refused by the controller: argument out of range");
}

TEST_F(ClientTest, SetCodeBreakingOneOfNIsRefused) {
  expect_rejected(client->set_code(0, code_of("1233"), true), proto::Status::kBadCode,
                  "invalid code");
}

TEST_F(ClientTest, SelectCode) {
  ASSERT_TRUE(client->set_code(1, code_of(kCode), true).ok());
  const auto selected = client->select_code(1);
  ASSERT_TRUE(selected.ok());
  EXPECT_EQ(selected.value().active_code_id, 1);
  expect_rejected(client->select_code(5), proto::Status::kNoSuchCode, "no code stored");
}

TEST_F(ClientTest, SetTiming) {
  ASSERT_TRUE(client->set_timing({250, 0, 0, {}}).ok());
  EXPECT_EQ(client->status().value().slot_time_us, 250u);
  expect_rejected(client->set_timing({0, 0, 0, {}}), proto::Status::kOutOfRange,
                  "SetTiming refused");
}

TEST_F(ClientTest, SetMode) {
  ASSERT_TRUE(client->set_mode(proto::SyncMode::kFreeRun, false).ok());
  EXPECT_EQ(client->status().value().sync_mode,
            static_cast<std::uint8_t>(proto::SyncMode::kFreeRun));
  ASSERT_TRUE(client->set_mode(proto::SyncMode::kSlave, false).ok());
  arm_with_code();
  expect_rejected(client->set_mode(proto::SyncMode::kMaster, false), proto::Status::kBadState,
                  "current state");
}

TEST_F(ClientTest, SetBrightness) {
  ASSERT_TRUE(client->set_brightness({{100, 200, 300, 0}}).ok());
  expect_rejected(client->set_brightness({{1001, 0, 0, 0}}), proto::Status::kOutOfRange,
                  "SetBrightness refused");
}

TEST_F(ClientTest, SetGuard) {
  proto::SetGuardRequest guard{};
  guard.max_on_time_us.fill(10'000);
  guard.max_duty_permille.fill(400);
  ASSERT_TRUE(client->set_guard(guard).ok());
  guard.max_duty_permille[0] = 0;
  expect_rejected(client->set_guard(guard), proto::Status::kOutOfRange, "SetGuard refused");
  // Above the product board's compiled ceiling (50 %): refused, by name.
  guard.max_duty_permille.fill(800);
  expect_rejected(client->set_guard(guard), proto::Status::kAboveCeiling,
                  "SetGuard refused by the controller: above the LED ceiling compiled into the "
                  "firmware (status 14)");
}

// SaveConfig erases a flash sector (up to 2 s) before it can answer: the
// client waits for it instead of timing out and sending it again (which erased
// a second time and still reported a timeout).
TEST_F(ClientTest, SaveConfigWaitsForTheSectorEraseWithoutResending) {
  vc->hold_replies(true);
  std::thread release([this] {
    std::this_thread::sleep_for(milliseconds(400));  // 4 x the reply timeout
    vc->hold_replies(false);
  });
  const auto saved = client->save_config();
  release.join();
  ASSERT_TRUE(saved.ok()) << saved.error().message;
  EXPECT_EQ(client->stats().retries, 0u);
}

TEST_F(ClientTest, ArmAndDisarm) {
  expect_rejected(client->arm(), proto::Status::kNoSuchCode, "Arm refused");
  arm_with_code();
  EXPECT_EQ(client->status().value().state,
            static_cast<std::uint8_t>(proto::ControllerState::kArmed));
  ASSERT_TRUE(client->disarm().ok());
  EXPECT_EQ(client->status().value().state,
            static_cast<std::uint8_t>(proto::ControllerState::kIdle));
}

TEST_F(ClientTest, Status) {
  const auto status = client->status();
  ASSERT_TRUE(status.ok());
  EXPECT_EQ(status.value().active_code_id, proto::kNoCode);
  // A GetStatus with a payload is malformed: BadLength.
  std::array<std::uint8_t, 5> raw{static_cast<std::uint8_t>(proto::Command::kGetStatus), 0, 1, 0,
                                  7};
  const auto reply = client->exchange_raw(raw);
  ASSERT_TRUE(reply.ok());
  EXPECT_EQ(reply.value()[3], static_cast<std::uint8_t>(proto::Status::kBadLength));
}

TEST_F(ClientTest, SelfTest) {
  vc->take_led_transitions();
  const auto result = client->self_test(1000);
  ASSERT_TRUE(result.ok()) << result.error().message;
  EXPECT_EQ(result.value().leds_stepped, 3);
  vc->advance_us(result.value().duration_us);
  const auto transitions = vc->take_led_transitions();
  ASSERT_GE(transitions.size(), 4u);
  EXPECT_EQ(transitions.back().led_mask, 0);
  expect_rejected(client->self_test(0), proto::Status::kOutOfRange, "SelfTest refused");
}

TEST_F(ClientTest, SaveConfig) {
  ASSERT_TRUE(client->set_code(0, code_of(kCode), true).ok());
  const auto saved = client->save_config();
  ASSERT_TRUE(saved.ok());
  EXPECT_GT(saved.value().bytes_written, 0u);
  ASSERT_TRUE(client->select_code(0).ok());
  ASSERT_TRUE(client->arm().ok());
  expect_rejected(client->save_config(), proto::Status::kBadState, "SaveConfig refused");
}

TEST_F(ClientTest, EnterBootloader) {
  std::array<std::uint8_t, 8> wrong_magic{
      static_cast<std::uint8_t>(proto::Command::kEnterBootloader), 0, 4, 0, 1, 2, 3, 4};
  const auto refused = client->exchange_raw(wrong_magic);
  ASSERT_TRUE(refused.ok());
  EXPECT_EQ(refused.value()[3], static_cast<std::uint8_t>(proto::Status::kOutOfRange));
  ASSERT_TRUE(client->enter_bootloader().ok());
  EXPECT_TRUE(vc->in_bootloader());
  const auto after = client->status();
  ASSERT_FALSE(after.ok());
  EXPECT_EQ(after.error().kind, ErrorKind::kGone);
}

// --- events ------------------------------------------------------------------

TEST_F(ClientTest, EventsArriveInOrderWithEncoderDeltas) {
  arm_with_code();
  for (int i = 0; i < 10; ++i) {
    vc->expose(6000);
    vc->add_encoder_counts(5);
    vc->advance_us(4000);
  }
  for (std::uint32_t frame = 1; frame <= 10; ++frame) {
    const auto notice = client->next_event(milliseconds(1000));
    ASSERT_TRUE(notice.has_value()) << "frame " << frame;
    EXPECT_EQ(notice->event.frame_counter, frame);
    EXPECT_EQ(notice->frames_missing_before, 0u);
    EXPECT_EQ(notice->event.slot_count, kCode.size());
    EXPECT_EQ(notice->event.code_id, 0);
  }
  EXPECT_EQ(client->stats().frames_missing, 0u);
}

TEST_F(ClientTest, LostEventsAreReportedAsAGap) {
  arm_with_code();
  // The host stops reading: the controller's 16-event queue overflows.
  vc->set_responsive(false);
  for (int i = 0; i < 20; ++i) vc->expose(6000);
  vc->set_responsive(true);
  std::vector<EventNotice> seen;
  while (seen.size() < 16)
    if (auto notice = client->next_event(milliseconds(1000)))
      seen.push_back(*notice);
    else
      break;
  ASSERT_EQ(seen.size(), 16u);
  vc->expose(6000);
  while (auto notice = client->next_event(milliseconds(300))) seen.push_back(*notice);
  ASSERT_EQ(seen.size(), 17u);
  EXPECT_EQ(seen[15].event.frame_counter, 16u);
  EXPECT_EQ(seen[16].event.frame_counter, 21u);
  EXPECT_EQ(seen[16].frames_missing_before, 4u);
  EXPECT_EQ(client->stats().frames_missing, 4u);
  EXPECT_EQ(client->status().value().events_dropped, 4u);
}

TEST_F(ClientTest, EventHandlerReceivesEvents) {
  std::atomic<int> handled{0};
  client->set_event_handler([&](const EventNotice&) { ++handled; });
  arm_with_code();
  for (int i = 0; i < 5; ++i) vc->expose(6000);
  for (int i = 0; i < 200 && handled < 5; ++i) std::this_thread::sleep_for(milliseconds(5));
  EXPECT_EQ(handled, 5);
  EXPECT_FALSE(client->next_event(milliseconds(10)).has_value());
}

// --- timeouts, stale replies, unplug, reconnect ------------------------------

TEST_F(ClientTest, UnresponsiveControllerTimesOutWithinTheBound) {
  vc->set_responsive(false);
  const auto start = std::chrono::steady_clock::now();
  const auto result = client->status();
  const auto took = std::chrono::steady_clock::now() - start;
  ASSERT_FALSE(result.ok());
  EXPECT_EQ(result.error().kind, ErrorKind::kTimeout);
  EXPECT_NE(result.error().message.find("no reply from virtual controller"), std::string::npos)
      << result.error().message;
  EXPECT_NE(result.error().message.find("GetStatus within 100 ms (2 attempts)"), std::string::npos)
      << result.error().message;
  EXPECT_EQ(client->stats().retries, 1u);
  EXPECT_GE(took, milliseconds(200));
  EXPECT_LT(took, milliseconds(1000));
  vc->set_responsive(true);
  EXPECT_TRUE(client->status().ok());
}

TEST_F(ClientTest, ReplyTimeoutBelowOneMillisecondIsWaitedAndNamed) {
  // A sub-millisecond timeout (the device_client fuzz target uses one) still waits for
  // the reply, and the message gives it in microseconds rather than as "0 ms".
  ClientOptions options = fast_options();
  options.reply_timeout = std::chrono::microseconds(500);
  connect_client(options);
  vc->set_responsive(false);
  const auto start = std::chrono::steady_clock::now();
  const auto result = client->status();
  const auto took = std::chrono::steady_clock::now() - start;
  ASSERT_FALSE(result.ok());
  EXPECT_EQ(result.error().kind, ErrorKind::kTimeout);
  EXPECT_NE(result.error().message.find("GetStatus within 500 us (2 attempts)"), std::string::npos)
      << result.error().message;
  EXPECT_GE(took, std::chrono::microseconds(1000));
  vc->set_responsive(true);
}

TEST_F(ClientTest, LateRepliesAreDiscardedAndCounted) {
  vc->hold_replies(true);
  const auto result = client->status();
  ASSERT_FALSE(result.ok());
  EXPECT_EQ(result.error().kind, ErrorKind::kTimeout);
  vc->hold_replies(false);  // both attempts' replies arrive now, too late
  const auto next = client->status();
  ASSERT_TRUE(next.ok()) << next.error().message;
  EXPECT_EQ(client->stats().stale_replies, 2u);
}

TEST_F(ClientTest, UnpluggedControllerFailsCommandsAfterTheReconnectWait) {
  client.reset();
  ClientOptions options = fast_options();
  options.reconnect_wait = milliseconds(150);
  connect_client(options);
  vc->unplug();
  const auto result = client->status();
  ASSERT_FALSE(result.ok());
  EXPECT_EQ(result.error().kind, ErrorKind::kGone);
  EXPECT_NE(result.error().message.find("did not come back within 150 ms"), std::string::npos)
      << result.error().message;
  EXPECT_TRUE(notices.contains("link lost"));
  EXPECT_EQ(vc->led_mask(), 0);
}

TEST_F(ClientTest, ReconnectRestoresCodeSettingsAndArmedState) {
  arm_with_code();
  ASSERT_TRUE(client->set_code(4, code_of("124124"), true).ok());
  vc->expose(6000);
  ASSERT_TRUE(client->next_event(milliseconds(500)).has_value());
  vc->unplug();
  for (int i = 0; i < 200 && client->connected(); ++i) std::this_thread::sleep_for(milliseconds(2));
  EXPECT_FALSE(client->connected());
  vc->plug_in();                         // boots with factory settings: nothing was saved
  const auto status = client->status();  // waits for the reconnect
  ASSERT_TRUE(status.ok()) << status.error().message;
  EXPECT_EQ(status.value().codes_stored, 0b10001);
  EXPECT_EQ(status.value().active_code_id, 0);
  EXPECT_EQ(status.value().slot_time_us, 100u);
  EXPECT_EQ(status.value().state, static_cast<std::uint8_t>(proto::ControllerState::kArmed));
  EXPECT_EQ(client->stats().reconnects, 1u);
  EXPECT_TRUE(
      notices.contains("is back: re-sent timing, code 0, code 4, selected code 0 and armed again"));
  vc->expose(6000);
  const auto event = client->next_event(milliseconds(500));
  ASSERT_TRUE(event.has_value());
  EXPECT_EQ(event->event.frame_counter, 1u);
  EXPECT_EQ(event->frames_missing_before, 0u);
}

}  // namespace
}  // namespace flutterscan::device
