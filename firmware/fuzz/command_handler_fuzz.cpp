// libFuzzer target: arbitrary HID request reports, interleaved with strobe
// pulses, encoder counts, virtual time, USB resets, port faults, flash
// corruption and reboots, into a Controller + CommandHandler on the SimPort.
// The input format is in fuzz_input.hpp; tools/fuzz builds and runs this.
//
// Checked after every step (abort on violation):
// - every reply is a 64-byte report echoing the request's command and
//   sequence, with a known status, a payload of the size its command and
//   status call for, and zero padding; framing errors get the status the
//   protocol prescribes; an error reply changed nothing;
// - every exposure event report is well-formed;
// - the port agrees with the controller's state: a slot table plays only while
//   exposing or self-testing, the frame timer runs only while armed in master
//   or free-run mode, and otherwise every LED is off (checked whenever no port
//   callback is on its way: with the product port's timing, board byte bit 6,
//   a pre-armed table starts on its edge in hardware and the controller hears
//   of it an interrupt latency later, or after the main loop's interrupt lock,
//   which every request holds);
// - the compiled ceiling (BoardConfig::ceiling): the guard in force never
//   exceeds its on-time and duty, the brightness never its current;
// - no LED has a joined run longer than the thermal guard's max_on_time_us
//   (nor the ceiling's): runs less than the ceiling's min_off_time_us apart
//   are one run, the gap counted as on, across exposures, self tests and
//   reboots of every kind (the LED record is the port's, which a reboot keeps);
// - the duty cap (docs/hardware.md, "Thermal guard"): for every two slot
//   tables the port started one after the other (exposures and self tests
//   alike, across Arm, Disarm, mode and code changes and reboots), at a
//   and then b, each LED's energy (on-time x brightness, per mille of full
//   current) from b until the next table starts is at most its
//   max_duty_permille (in force at b) of b - a. A reboot, whatever its cause,
//   counts as a table start that lit nothing (the LEDs keep their heat: the
//   duty window starts full at boot). Measured from the port's record of
//   table starts and LED writes, not the controller's bookkeeping;
// - USB (ops kSetup..kDfuDownload, through the USB device core on a
//   SimUsbController): every control transfer gets exactly one answer of the
//   right direction and no more data than wLength; every report on the HID IN
//   endpoint is well-formed: an exposure event in sequence, or the reply to
//   the oldest request the OUT endpoint accepted (command and sequence
//   echoed), and once the IN endpoint is empty, free and the device holds no
//   request, every accepted request has been answered (no reply dropped); a
//   bus reset disarms the controller (every LED off);
// - DFU mode (a bootloader on a SimFlash): sectors 0 and 1 (bootloader,
//   config) are never erased or written, GETSTATUS is well-formed, and a
//   device ready to start the application holds an image the checker accepts;
// then the input ends with a Disarm report and the clock runs on: every LED
// must be off, the last recorded LED write included.
//
// Work per input is bounded (operations, LED writes + port callbacks, virtual
// time, strobe pulses), so no input hangs.

#include <algorithm>
#include <array>
#include <bitset>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "flutterscan/common/protocol.hpp"
#include "flutterscan/firmware/boot_decision.hpp"
#include "flutterscan/firmware/command_handler.hpp"
#include "flutterscan/firmware/config_store.hpp"
#include "flutterscan/firmware/controller.hpp"
#include "flutterscan/firmware/sim/sim_board.hpp"
#include "flutterscan/firmware/sim/sim_flash.hpp"
#include "flutterscan/firmware/sim/sim_security_floor.hpp"
#include "flutterscan/firmware/sim/sim_port.hpp"
#include "flutterscan/firmware/sim/sim_usb_controller.hpp"
#include "flutterscan/firmware/usb/application_usb.hpp"
#include "flutterscan/firmware/usb/bootloader_usb.hpp"
#include "flutterscan/firmware/usb/dfu.hpp"
#include "fuzz_input.hpp"

namespace {

namespace proto = flutterscan::protocol;
namespace fw = flutterscan::firmware;
using fw::fuzz::Op;

// Bounds on the work of one input.
constexpr int kMaxOps = 300;
constexpr std::size_t kMaxWork = 20'000;             // LED writes + port callbacks
constexpr std::uint64_t kMaxVirtualUs = 60'000'000;  // clock advanced by the ops
constexpr int kMaxStrobePulses = 64;
constexpr int kMaxUploadChunks = 6;
// Clock steps while the frame timer runs (at most one tick per step).
constexpr std::uint64_t kFrameStepUs = proto::kMinFramePeriodUs;
// Virtual time each request report takes: commands run on the MCU one after
// another, not at one instant (without it, Disarm, Arm and a strobe in one
// microsecond would look like an LED that never went off).
constexpr std::uint64_t kReportGapUs = 1;
// After the final Disarm: longer than the longest exposure (256 slots x 10 ms).
constexpr std::uint64_t kSettleUs = 3'000'000;
// USB: the devices' descriptors and unique ID, and the bounds of one DFU download op.
constexpr auto kAppDevice = fw::usb::application_device_descriptor(0x0123);
constexpr auto kBootDevice = fw::usb::bootloader_device_descriptor(0x0100);
constexpr std::array<std::uint8_t, 12> kUniqueId{1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12};
constexpr std::size_t kMaxDfuImage = 20 * 1024;

[[noreturn]] void fail(const char* what, int line) {
  std::fprintf(stderr, "command_handler_fuzz: invariant violated (line %d): %s\n", line, what);
  std::abort();
}

// FUZZ_TRACE=1 in the environment: one line per report and event (for
// reading what a seed or a crash does; slow).
const bool g_trace = std::getenv("FUZZ_TRACE") != nullptr;

#define FUZZ_CHECK(cond)                \
  do {                                  \
    if (!(cond)) fail(#cond, __LINE__); \
  } while (false)

/// Reads the input; missing bytes read as 0.
class Reader {
 public:
  explicit Reader(std::span<const std::uint8_t> data) : data_(data) {}
  bool empty() const { return pos_ >= data_.size(); }
  std::uint8_t u8() { return empty() ? 0 : data_[pos_++]; }
  std::uint16_t u16() {
    const std::uint16_t lo = u8();
    return static_cast<std::uint16_t>(lo | (u8() << 8));
  }
  std::int32_t i32() {
    std::uint32_t v = 0;
    for (int i = 0; i < 4; ++i) v |= static_cast<std::uint32_t>(u8()) << (8 * i);
    return static_cast<std::int32_t>(v);
  }
  std::uint64_t time() {
    const std::uint64_t v = u16();
    return v << (u8() % 8);
  }
  /// Up to n bytes (fewer at the end of the input).
  std::span<const std::uint8_t> take(std::size_t n) {
    const std::size_t k = std::min(n, data_.size() - std::min(pos_, data_.size()));
    const auto out = data_.subspan(pos_, k);
    pos_ += k;
    return out;
  }

 private:
  std::span<const std::uint8_t> data_;
  std::size_t pos_ = 0;
};

fw::BoardConfig board_from(std::uint8_t b) {
  static constexpr std::array<std::array<std::uint8_t, 4>, fw::fuzz::kPinLayouts> kLayouts{{
      {0, 1, 2, 3},
      {3, 2, 1, 0},
      {15, 8, 7, 0},
      {5, 9, 12, 14},
  }};
  fw::BoardConfig board;
  board.pins.led_count = 1 + (b & 3);
  board.pins.pins = kLayouts[(b >> 2) & 3];
  board.board_id = 0x0405;
  board.firmware_major = 1;
  board.firmware_minor = 2;
  board.firmware_patch = 3;
  board.build_id = 0xF022F022;
  // The default guard is within the ceiling, as on every image.
  switch ((b >> 4) & 3) {
    case 0:
      break;  // the BoardConfig defaults: the product's guard and ceiling
    case 1:  // a ceiling of 1 ms, 100 % at 70 % current, 500 us off joins
      board.ceiling = {{1'000, 1'000, 1'000, 1'000}, {1'000, 1'000, 1'000, 1'000},
                       {700, 700, 700, 700}, 500};
      board.default_guard = {{1'000, 1'000, 1'000, 1'000}, {1'000, 1'000, 1'000, 1'000}};
      break;
    case 2:
      board.default_guard = {{10, 10, 10, 10}, {100, 100, 100, 100}};
      break;
    default:  // the protocol's limits as the ceiling; only touching runs join
      board.ceiling.max_on_time_us.fill(proto::kMaxGuardOnTimeUs);
      board.ceiling.max_duty_permille.fill(proto::kDutyFullScale);
      board.ceiling.max_current_permille.fill(proto::kBrightnessFullScale);
      board.ceiling.min_off_time_us = 1;
      board.default_guard.max_on_time_us.fill(proto::kMaxGuardOnTimeUs);
      board.default_guard.max_duty_permille.fill(proto::kDutyFullScale);
      break;
  }
  return board;
}

/// Request payload size of a known command.
std::size_t request_payload_size(proto::Command command) {
  switch (command) {
    case proto::Command::kSetCode:
      return sizeof(proto::SetCodeRequest);
    case proto::Command::kSelectCode:
      return sizeof(proto::SelectCodeRequest);
    case proto::Command::kSetTiming:
      return sizeof(proto::SetTimingRequest);
    case proto::Command::kSetMode:
      return sizeof(proto::SetModeRequest);
    case proto::Command::kSetBrightness:
      return sizeof(proto::SetBrightnessRequest);
    case proto::Command::kSetGuard:
      return sizeof(proto::SetGuardRequest);
    case proto::Command::kSelfTest:
      return sizeof(proto::SelfTestRequest);
    case proto::Command::kEnterBootloader:
      return sizeof(proto::EnterBootloaderRequest);
    default:
      return 0;
  }
}

/// Reply payload size of a known command answered with kOk.
std::size_t ok_reply_payload_size(proto::Command command) {
  switch (command) {
    case proto::Command::kGetInfo:
      return sizeof(proto::InfoReply);
    case proto::Command::kSetCode:
      return sizeof(proto::SetCodeReply);
    case proto::Command::kSelectCode:
      return sizeof(proto::SelectCodeReply);
    case proto::Command::kGetStatus:
      return sizeof(proto::StatusReply);
    case proto::Command::kSelfTest:
      return sizeof(proto::SelfTestReply);
    case proto::Command::kSaveConfig:
      return sizeof(proto::SaveConfigReply);
    default:
      return 0;
  }
}

/// The status the protocol prescribes for a request that fails framing
/// (docs/protocol.md), written here independently of protocol.hpp's parser;
/// nullopt if the request gets past framing to its command.
std::optional<proto::Status> framing_status(std::span<const std::uint8_t> request) {
  if (request.size() < proto::kHeaderSize || request.size() > proto::kReportSize)
    return proto::Status::kBadLength;
  if (request[2] > request.size() - proto::kHeaderSize) return proto::Status::kBadLength;
  if (request[3] != 0) return proto::Status::kBadHeader;
  if (request[0] < 0x01 || request[0] > 0x0D) return proto::Status::kUnknownCommand;
  if (request[2] != request_payload_size(static_cast<proto::Command>(request[0])))
    return proto::Status::kBadLength;
  return std::nullopt;
}

bool same_settings(const fw::ControllerSettings& a, const fw::ControllerSettings& b) {
  for (std::size_t i = 0; i < a.codes.size(); ++i) {
    const auto& x = a.codes[i];
    const auto& y = b.codes[i];
    if (x.present != y.present) return false;
    if (!x.present) continue;
    if (x.code.leds() != y.code.leds() || x.code.length() != y.code.length()) return false;
    if (!std::equal(x.code.masks().begin(), x.code.masks().end(), y.code.masks().begin()))
      return false;
  }
  return a.selected_code == b.selected_code && a.timing.slot_time_us == b.timing.slot_time_us &&
         a.timing.frame_period_us == b.timing.frame_period_us &&
         a.timing.source == b.timing.source && a.mode.sync == b.mode.sync &&
         a.mode.strobe_active_low == b.mode.strobe_active_low &&
         a.brightness_permille == b.brightness_permille &&
         a.guard.max_on_time_us == b.guard.max_on_time_us &&
         a.guard.max_duty_permille == b.guard.max_duty_permille;
}

/// Status replies equal but for the uptime.
bool same_status(proto::StatusReply a, proto::StatusReply b) {
  a.uptime_us = 0;
  b.uptime_us = 0;
  return std::memcmp(&a, &b, sizeof(a)) == 0;
}

/// Sits between the SimPort and the Controller: counts callbacks (the work
/// budget) and checks that a slot table ends with every LED off.
class Interposer final : public fw::PortListener {
 public:
  fw::Controller* target = nullptr;
  const fw::sim::SimPort* port = nullptr;
  std::size_t callbacks = 0;

  void on_strobe_edge(bool active, std::uint64_t time_us) override {
    ++callbacks;
    target->on_strobe_edge(active, time_us);
  }
  void on_slot_table_done(std::uint64_t time_us) override {
    ++callbacks;
    FUZZ_CHECK(port->led_mask() == 0);
    target->on_slot_table_done(time_us);
  }
  void on_frame_tick(std::uint64_t time_us) override {
    ++callbacks;
    target->on_frame_tick(time_us);
  }
};

using OnLimits = std::array<std::uint32_t, flutterscan::kMaxLeds>;

class Harness {
 public:
  explicit Harness(std::uint8_t board_byte)
      : board_byte_(board_byte), board_(board_from(board_byte)), port_(board_.pins) {
    interposer_.port = &port_;
    if ((board_byte & fw::fuzz::kBoardTiming) != 0) {
      const bool slow = (board_byte & fw::fuzz::kBoardSlowInterrupts) != 0;
      port_.set_interrupt_latency_us(slow ? 25 : 3);
      lock_us_ = slow ? 150 : 10;
    }
    boot();
  }
  Harness(const Harness&) = delete;
  Harness& operator=(const Harness&) = delete;

  void run(Reader& in) {
    for (int ops = 0; ops < kMaxOps && !in.empty() && !exhausted(); ++ops) {
      const OnLimits before = guard_limits();
      step(in);
      observe(min_limits(before, guard_limits()));
    }
    finish();
  }

 private:
  // Setup ------------------------------------------------------------------
  void boot() {
    app_usb_.reset();
    usb_.reset();
    handler_.reset();
    controller_.reset();
    controller_.emplace(port_, board_);
    interposer_.target = &*controller_;
    port_.set_listener(&interposer_);
    handler_.emplace(*controller_);
    controller_->start();
    event_top_ = -1;
    next_direct_event_ = 0;
    next_usb_event_ = 0;
    events_seen_.reset();
    usb_.emplace();
    app_usb_.emplace(*usb_, *controller_, *handler_, kAppDevice, kUniqueId);
    usb_->attach(&*app_usb_);
    pending_replies_.clear();
  }

  // Operations ---------------------------------------------------------------
  void step(Reader& in) {
    switch (static_cast<Op>(in.u8() % fw::fuzz::kOpCount)) {
      case Op::kRawReport: {
        const std::size_t length = in.u8() % (proto::kReportSize + 2);
        feed_report(in.take(length));
        break;
      }
      case Op::kReport: {
        const auto command = static_cast<std::uint8_t>(1 + in.u8() % 13);
        const std::uint8_t sequence = in.u8();
        std::array<std::uint8_t, proto::kMaxPayloadSize> payload{};
        const std::size_t size = request_payload_size(static_cast<proto::Command>(command));
        const auto bytes = in.take(size);
        std::copy(bytes.begin(), bytes.end(), payload.begin());
        std::array<std::uint8_t, proto::kReportSize> report{};
        FUZZ_CHECK(proto::encode_raw(command, sequence, proto::Status::kOk,
                                     std::span<const std::uint8_t>(payload.data(), size),
                                     report) == proto::kReportSize);
        feed_report(report);
        break;
      }
      case Op::kUploadCode:
        upload_code(in);
        break;
      case Op::kStrobes: {
        const int count = 1 + in.u8() % 8;
        const std::uint64_t delay = in.time();
        const std::uint64_t period = in.time();
        const auto width = static_cast<std::uint32_t>(in.time());
        for (int i = 0; i < count && strobe_pulses_ < kMaxStrobePulses; ++i, ++strobe_pulses_)
          port_.inject_strobe(port_.now_us() + delay + static_cast<std::uint64_t>(i) * period,
                              width);
        break;
      }
      case Op::kAdvance:
        advance(in.time());
        break;
      case Op::kEncoder: {
        const bool velocity = (in.u8() & 1) != 0;
        const std::int32_t value = in.i32();
        if (velocity)
          port_.set_encoder_velocity(value);
        else
          port_.add_encoder_counts(value);
        break;
      }
      case Op::kPoll:
        controller_->poll();
        break;
      case Op::kReadEvents:
        read_events(1 + in.u8() % 20);
        break;
      case Op::kUsbReset:
        controller_->on_usb_reset();
        FUZZ_CHECK(controller_->state() == proto::ControllerState::kIdle);
        FUZZ_CHECK((controller_->status().flags & proto::kStatusUploadInProgress) == 0);
        break;
      case Op::kPortFault:
        controller_->on_port_fault();
        FUZZ_CHECK(controller_->state() == proto::ControllerState::kFault);
        break;
      case Op::kPortFailures: {
        const std::uint8_t b = in.u8();
        port_.set_slot_timer_fails((b & 1) != 0);
        port_.set_flash_fails((b & 2) != 0);
        break;
      }
      case Op::kReboot: {
        const auto cause = static_cast<fw::ResetCause>(in.u8() % 3);
        const OnLimits before = guard_limits();
        port_.set_reset_cause(cause);
        boot();
        // Controller::start turns every LED off before it loads the stored
        // config, whose guard may be stricter: a run that this all-off write
        // ends was on under the guard in force before (crashes/reboot-ends-run-
        // under-the-old-guard). LEDs lit after the boot: under both, as for any op.
        observe(before);
        // Every kind of boot: the duty window starts full, as if a table that
        // lit nothing started now (the LEDs have their own supply).
        duty_start(port_.now_us());
        FUZZ_CHECK(port_.led_mask() == 0);
        break;
      }
      case Op::kFlashPoke: {
        const std::uint16_t where = in.u16();
        const std::size_t offset =
            (where >> 1) % (sizeof(fw::ConfigImage) + sizeof(fw::ConfigCommit));
        port_.flash_page(where & 1)[offset] = in.u8();
        break;
      }
      case Op::kSetup:
        control_transfer(*usb_, in);
        usb_main_loop();
        break;
      case Op::kHidOut: {
        const std::size_t length = in.u8() % (proto::kReportSize + 2);
        hid_out(in.take(length));
        break;
      }
      case Op::kHidIn:
        hid_in(1 + in.u8() % 8);
        break;
      case Op::kBusReset:
        bus_reset();
        break;
      case Op::kEnumerate: {
        bus_reset();
        const auto address = static_cast<std::uint16_t>(1 + in.u8() % 127);
        FUZZ_CHECK(!usb_->control_transfer(0x00, 5, address, 0, 0).stalled);
        FUZZ_CHECK(!usb_->control_transfer(0x00, 9, 1, 0, 0).stalled);
        usb_main_loop();
        break;
      }
      case Op::kDfuSetup:
        control_transfer(dfu().usb, in);
        check_dfu();
        break;
      case Op::kDfuDownload:
        dfu_download(in);
        check_dfu();
        break;
      case Op::kEp0Packets:
        ep0_packets(in);
        break;
      case Op::kCount:
        break;
    }
  }

  // USB ----------------------------------------------------------------------
  /// One main-loop pass of the application image.
  void usb_main_loop() {
    app_usb_->poll();
    FUZZ_CHECK(usb_->ep0_protocol_errors() == 0);
  }

  /// A SETUP from the input (8 bytes, then the OUT data stage) on `usb`.
  void control_transfer(fw::sim::SimUsbController& usb, Reader& in) {
    std::array<std::uint8_t, 8> setup{};
    const auto bytes = in.take(8);
    std::copy(bytes.begin(), bytes.end(), setup.begin());
    const auto packet = fw::usb::SetupPacket::parse(setup);
    const auto data = packet.is_in() ? std::span<const std::uint8_t>()
                                     : in.take(std::min<std::size_t>(packet.length, 1024));
    const int errors_before = usb.ep0_protocol_errors();
    const fw::sim::ControlResult r = usb.control_transfer(setup, data);
    if (g_trace)
      std::fprintf(stderr, "SETUP %02x %02x %04x %04x %04x -> %s %zu bytes\n", packet.request_type,
                   packet.request, packet.value, packet.index, packet.length,
                   r.stalled ? "STALL" : "ok", r.data.size());
    FUZZ_CHECK(usb.ep0_protocol_errors() == errors_before);
    FUZZ_CHECK(r.data.size() <= packet.length);
    if (!packet.is_in()) FUZZ_CHECK(r.data.empty());
  }

  /// Where the packet-level transfer of one device stands, as the host saw it.
  struct Ep0Transfer {
    bool in = false;           ///< the last SETUP's direction
    std::uint16_t length = 0;  ///< its wLength
    std::size_t in_bytes = 0;  ///< IN data received since it
    bool in_ended = false;     ///< a short (or zero-length) IN packet ended the data stage
  };

  /// Endpoint-0 transactions one at a time on the application or the DFU device.
  void ep0_packets(Reader& in) {
    const bool to_dfu = (in.u8() & 1) != 0;
    fw::sim::SimUsbController& usb = to_dfu ? dfu().usb : *usb_;
    Ep0Transfer& t = to_dfu ? dfu_ep0_ : app_ep0_;
    const int count = 1 + in.u8() % 24;
    for (int i = 0; i < count && !in.empty(); ++i) {
      switch (in.u8() % 3) {
        case 0: {
          std::array<std::uint8_t, 8> setup{};
          const auto bytes = in.take(8);
          std::copy(bytes.begin(), bytes.end(), setup.begin());
          const auto packet = fw::usb::SetupPacket::parse(setup);
          t = Ep0Transfer{packet.is_in(), packet.length, 0, false};
          usb.setup_packet(setup);
          if (g_trace)
            std::fprintf(stderr, "%s SETUP packet %02x %02x %04x %04x %04x -> stage %d\n",
                         to_dfu ? "dfu" : "app", packet.request_type, packet.request, packet.value,
                         packet.index, packet.length, static_cast<int>(usb.ep0_stage()));
          break;
        }
        case 1: {
          const std::size_t length = in.u8() % (fw::usb::kEp0MaxPacket + 1);
          const auto bytes = in.take(length);
          const fw::sim::Ep0Handshake h = usb.ep0_out_packet(bytes);
          if (g_trace)
            std::fprintf(stderr, "%s OUT packet %zu bytes -> %d\n", to_dfu ? "dfu" : "app",
                         bytes.size(), static_cast<int>(h));
          break;
        }
        default: {
          const fw::sim::Ep0InPacket p = usb.ep0_in_packet();
          if (g_trace)
            std::fprintf(stderr, "%s IN packet -> %d, %zu bytes\n", to_dfu ? "dfu" : "app",
                         static_cast<int>(p.handshake), p.data.size());
          FUZZ_CHECK(p.data.size() <= fw::usb::kEp0MaxPacket);
          if (p.handshake != fw::sim::Ep0Handshake::kAck) FUZZ_CHECK(p.data.empty());
          if (p.handshake == fw::sim::Ep0Handshake::kAck &&
              usb.ep0_stage() != fw::sim::Ep0Stage::kIdle) {
            // A data-stage packet: only for an IN request, never past wLength
            // or after the packet that ended the stage.
            FUZZ_CHECK(t.in);
            FUZZ_CHECK(!t.in_ended);
            t.in_bytes += p.data.size();
            FUZZ_CHECK(t.in_bytes <= t.length);
            if (p.data.size() < fw::usb::kEp0MaxPacket) t.in_ended = true;
          }
          break;
        }
      }
      if (to_dfu) {
        // check_dfu's own GETSTATUS would abort a transfer in progress.
        const fw::sim::Ep0Stage stage = usb.ep0_stage();
        check_dfu(stage == fw::sim::Ep0Stage::kIdle || stage == fw::sim::Ep0Stage::kStalled);
      } else {
        usb_main_loop();
      }
    }
  }

  void hid_out(std::span<const std::uint8_t> report) {
    advance(kReportGapUs);
    const fw::sim::OutResult r = usb_->interrupt_out(fw::usb::kHidOutEndpoint.address, report);
    if (r == fw::sim::OutResult::kAck)
      pending_replies_.push_back({report.size() > 0 ? report[0] : std::uint8_t{0},
                                  report.size() > 1 ? report[1] : std::uint8_t{0}});
    take_lock();
    usb_main_loop();
    release_lock();
  }

  void hid_in(int count) {
    constexpr std::uint8_t kIn = fw::usb::kHidInEndpoint.address;
    for (int i = 0; i < count; ++i) {
      usb_main_loop();
      const auto packet = usb_->interrupt_in(kIn);
      if (!packet) {
        // Nothing on a free, unhalted endpoint of a configured device that holds
        // no request: every accepted request has had its reply.
        if (app_usb_->device().configured() && !usb_->endpoint_halted(kIn) &&
            !app_usb_->hid().request_pending()) {
          FUZZ_CHECK(!app_usb_->hid().replies_pending());
          FUZZ_CHECK(pending_replies_.empty());
        }
        return;
      }
      FUZZ_CHECK(packet->size() == proto::kReportSize);
      const proto::MessageHeader h = proto::peek_header(*packet);
      // An event has status 0; a reply to a request whose command byte is
      // 0x80 (not a request) always carries an error status.
      if (h.command == static_cast<std::uint8_t>(proto::Command::kExposureEvent) && h.status == 0) {
        check_event_report(*packet, true);
        continue;
      }
      FUZZ_CHECK(!pending_replies_.empty());
      FUZZ_CHECK(h.command == pending_replies_.front()[0]);
      FUZZ_CHECK(h.sequence == pending_replies_.front()[1]);
      FUZZ_CHECK(h.status <= static_cast<std::uint8_t>(proto::Status::kAboveCeiling));
      FUZZ_CHECK(h.payload_length <= proto::kMaxPayloadSize);
      for (std::size_t k = proto::kHeaderSize + h.payload_length; k < proto::kReportSize; ++k)
        FUZZ_CHECK((*packet)[k] == 0);
      pending_replies_.pop_front();
    }
  }

  void bus_reset() {
    if (g_trace) std::fprintf(stderr, "bus reset\n");
    usb_->bus_reset();
    pending_replies_.clear();  // the host's transfers are void
    FUZZ_CHECK(controller_->state() == proto::ControllerState::kIdle);
    FUZZ_CHECK((controller_->status().flags & proto::kStatusUploadInProgress) == 0);
    FUZZ_CHECK(port_.led_mask() == 0);
    usb_main_loop();
  }

  // DFU mode -------------------------------------------------------------------
  // The F405's first 128 KiB (sectors 0..4: bootloader, config, the whole
  // application region), so each input's flash is cheap to make.
  static constexpr fw::FlashLayout kDfuFlash{
      std::span<const fw::FlashSector>(fw::kStm32f405FlashSectors).first(5), 5};
  /// The DFU flash, one for the process: reset() makes it as good as new
  /// without a fresh 128 KiB allocation (and its page faults) per input.
  static fw::sim::SimFlash& dfu_flash() {
    static fw::sim::SimFlash flash{kDfuFlash};
    return flash;
  }
  struct DfuDevice {
    fw::sim::SimFlash& flash = dfu_flash();
    fw::sim::SimSecurityFloor floor;
    fw::sim::SimUsbController usb;
    fw::usb::BootloaderUsb boot{usb,       flash,       floor, kDfuFlash,
                                flutterscan::kStm32f405AppRegion, kBootDevice, kUniqueId};
    DfuDevice() {
      usb.attach(&boot);
      usb.bus_reset();
      usb.control_transfer(0x00, 5, 1, 0, 0);
      usb.control_transfer(0x00, 9, 1, 0, 0);
    }
  };

  /// The bootloader, made at its first use.
  DfuDevice& dfu() {
    if (!dfu_) {
      dfu_flash().reset();  // erased, nothing counted, as a fresh SimFlash
      dfu_ = std::make_unique<DfuDevice>();
    }
    return *dfu_;
  }

  fw::sim::ControlResult dfu_request(fw::usb::DfuRequest request, std::uint16_t value,
                                     std::span<const std::uint8_t> data = {}) {
    const bool in = request == fw::usb::DfuRequest::kGetStatus ||
                    request == fw::usb::DfuRequest::kGetState ||
                    request == fw::usb::DfuRequest::kUpload;
    return dfu().usb.control_transfer(
        in ? fw::usb::kDfuRequestIn : fw::usb::kDfuRequestOut, static_cast<std::uint8_t>(request),
        value, 0,
        static_cast<std::uint16_t>(request == fw::usb::DfuRequest::kGetStatus ? 6 : data.size()),
        data);
  }

  /// make_application_image(board, 1.2.3, size, seed), remembered: generating
  /// and stamping (a bitwise CRC) a 20 KiB image took a fifth of the time, and
  /// mutated inputs keep asking for the same few. A pure function of its
  /// arguments, so the cache changes no result.
  static std::vector<std::uint8_t> application_image(bool wrong_board, std::size_t size,
                                                     std::uint8_t seed) {
    struct Entry {
      std::uint32_t key = std::numeric_limits<std::uint32_t>::max();
      std::vector<std::uint8_t> image;
    };
    constexpr std::size_t kEntries = 64;
    static std::array<Entry, kEntries> cache;
    static std::size_t next_victim = 0;
    const auto key = static_cast<std::uint32_t>((wrong_board ? 1u << 24 : 0u) | size << 8 | seed);
    for (const Entry& e : cache)
      if (e.key == key) return e.image;
    Entry& e = cache[next_victim];
    next_victim = (next_victim + 1) % kEntries;
    e.key = key;
    e.image = fw::sim::make_application_image(
        wrong_board ? flutterscan::kBoardIdQemuNetduinoplus2 : flutterscan::kBoardIdStm32f405, 1, 2,
        3, size, seed);
    return e.image;
  }

  /// dfu-util's download of a generated image, optionally spoilt.
  void dfu_download(Reader& in) {
    const std::uint8_t seed = in.u8();
    const std::size_t size = 600 + in.u16() % (kMaxDfuImage - 600);
    const std::uint8_t spoil = in.u8();
    auto image = application_image((spoil & 1) != 0, size, seed);
    if (spoil & 2) image[size / 2 + 1] ^= 0x10;
    // Out of dfuERROR first, as dfu-util does.
    const auto status = dfu_request(fw::usb::DfuRequest::kGetStatus, 0);
    if (!status.stalled && status.data.size() == 6 &&
        status.data[4] == static_cast<std::uint8_t>(fw::usb::DfuState::kError))
      dfu_request(fw::usb::DfuRequest::kClrStatus, 0);
    else
      dfu_request(fw::usb::DfuRequest::kAbort, 0);
    std::uint16_t block = 0;
    for (std::size_t at = 0; at <= image.size(); at += 1024) {
      if ((spoil & 4) && block == 2) ++block;
      const auto chunk = std::span<const std::uint8_t>(image).subspan(
          at, std::min<std::size_t>(1024, image.size() - at));
      if (dfu_request(fw::usb::DfuRequest::kDnload, block++, chunk).stalled) return;
      if (spoil & 8) continue;
      for (int polls = 0; polls < 3; ++polls) {
        const auto s = dfu_request(fw::usb::DfuRequest::kGetStatus, 0);
        FUZZ_CHECK(!s.stalled && s.data.size() == 6);
        const auto state = static_cast<fw::usb::DfuState>(s.data[4]);
        if (state == fw::usb::DfuState::kError) return;
        if (state == fw::usb::DfuState::kDnloadIdle || state == fw::usb::DfuState::kDfuIdle) break;
      }
    }
  }

  /// The DFU device's invariants; `request_status`: GETSTATUS too (a control
  /// transfer of its own, which aborts a packet-level one in progress).
  void check_dfu(bool request_status = true) {
    DfuDevice& d = dfu();
    for (int sector = 0; sector < 2; ++sector) {
      FUZZ_CHECK(d.flash.erase_count(sector) == 0);
      FUZZ_CHECK(d.flash.program_count(sector) == 0);
    }
    FUZZ_CHECK(d.usb.ep0_protocol_errors() == 0);
    if (request_status) {
      const auto status = dfu_request(fw::usb::DfuRequest::kGetStatus, 0);
      if (!status.stalled) FUZZ_CHECK(status.data.size() == 6 && status.data[4] <= 10);
    }
    if (d.boot.leave_requested()) {
      const auto region = d.flash.read(flutterscan::kStm32f405AppRegion.load_address,
                                       flutterscan::kStm32f405AppRegion.max_size);
      FUZZ_CHECK(fw::choose_boot_target(false, region, flutterscan::kStm32f405AppRegion) ==
                 fw::BootTarget::kApplication);
    }
  }

  void upload_code(Reader& in) {
    const auto id = static_cast<std::uint8_t>(in.u8() % (proto::kMaxCodes + 1));
    const auto leds = static_cast<std::uint8_t>(in.u8() % (flutterscan::kMaxLeds + 1));
    const std::uint16_t slots_arg = in.u16();
    const std::uint8_t flags_arg = in.u8();
    const bool raw = (flags_arg & 0x80) != 0;
    const auto total = static_cast<std::uint16_t>(raw ? slots_arg : 1 + slots_arg % 256);
    const auto flags = static_cast<std::uint8_t>(raw ? (flags_arg >> 1) : (flags_arg & 1));
    const auto masks = in.take(std::min<std::size_t>(total, flutterscan::kMaxSlots));
    const auto all_leds = static_cast<std::uint8_t>((1u << leds) - 1u);
    std::uint16_t first = 0;
    for (int chunk = 0; chunk < kMaxUploadChunks && first < total; ++chunk) {
      proto::SetCodeRequest r{};
      r.code_id = id;
      r.led_count = leds;
      r.total_slots = total;
      r.first_slot = first;
      r.slot_count = static_cast<std::uint8_t>(
          std::min<std::size_t>(total - first, proto::kSlotsPerCodeChunk));
      r.flags = flags;
      for (std::size_t i = 0; i < r.slot_count; ++i) {
        const std::size_t slot = first + i;
        std::uint8_t mask = masks.empty() ? 1 : masks[slot % masks.size()];
        if (!raw) mask = static_cast<std::uint8_t>(mask & all_leds);
        r.masks[i] = mask;
      }
      std::array<std::uint8_t, proto::kReportSize> report{};
      FUZZ_CHECK(proto::encode_request(proto::Command::kSetCode, ++sequence_, r, report) ==
                 proto::kReportSize);
      if (feed_report(report) != proto::Status::kOk) break;
      first = static_cast<std::uint16_t>(first + r.slot_count);
    }
  }

  // Reports ------------------------------------------------------------------
  /// The main loop takes the interrupt lock: the hardware runs on for
  /// lock_us_ without callbacks, then the request is handled, then the lock ends.
  void take_lock() {
    if (lock_us_ == 0) return;
    port_.hold_interrupts_until(port_.now_us() + lock_us_);
    advance(lock_us_);
  }
  void release_lock() { port_.hold_interrupts_until(0); }

  proto::Status feed_report(std::span<const std::uint8_t> request) {
    advance(kReportGapUs);
    take_lock();
    const proto::Status status = feed_report_locked(request);
    release_lock();
    return status;
  }

  proto::Status feed_report_locked(std::span<const std::uint8_t> request) {
    const fw::ControllerSettings settings_before = controller_->settings();
    const proto::StatusReply status_before = controller_->status();
    const proto::ControllerState state_before = controller_->state();

    std::array<std::uint8_t, proto::kReportSize> reply;
    reply.fill(0xA5);
    FUZZ_CHECK(handler_->handle(request, reply) == proto::kReportSize);

    const proto::MessageHeader h = proto::peek_header(reply);
    if (g_trace)
      std::fprintf(stderr,
                   "%10llu us: request %zu bytes, command 0x%02x -> status %u (%s), state %u\n",
                   static_cast<unsigned long long>(port_.now_us()), request.size(), h.command,
                   h.status, proto::status_text(static_cast<proto::Status>(h.status)),
                   static_cast<unsigned>(controller_->state()));
    FUZZ_CHECK(h.command == (request.size() > 0 ? request[0] : 0));
    FUZZ_CHECK(h.sequence == (request.size() > 1 ? request[1] : 0));
    FUZZ_CHECK(h.status <= static_cast<std::uint8_t>(proto::Status::kAboveCeiling));
    FUZZ_CHECK(h.payload_length <= proto::kMaxPayloadSize);
    for (std::size_t i = proto::kHeaderSize + h.payload_length; i < proto::kReportSize; ++i)
      FUZZ_CHECK(reply[i] == 0);
    const auto status = static_cast<proto::Status>(h.status);
    const auto payload =
        std::span<const std::uint8_t>(reply).subspan(proto::kHeaderSize, h.payload_length);

    const auto unchanged = [&] {
      FUZZ_CHECK(same_settings(settings_before, controller_->settings()));
      FUZZ_CHECK(same_status(status_before, controller_->status()));
    };

    if (const auto framing = framing_status(request)) {
      FUZZ_CHECK(status == *framing);
      FUZZ_CHECK(h.payload_length == 0);
      unchanged();
      return status;
    }
    const auto command = static_cast<proto::Command>(request[0]);
    const auto args = request.subspan(proto::kHeaderSize, request[2]);
    if (status != proto::Status::kOk) {
      FUZZ_CHECK(h.payload_length == 0);
      unchanged();
      FUZZ_CHECK(controller_->state() == state_before);
      return status;
    }
    FUZZ_CHECK(h.payload_length == ok_reply_payload_size(command));

    switch (command) {
      case proto::Command::kGetInfo: {
        unchanged();
        const auto info = proto::decode_payload<proto::InfoReply>(payload).value();
        FUZZ_CHECK(info.protocol_major == proto::kProtocolMajor);
        FUZZ_CHECK(info.led_count == board_.pins.led_count);
        FUZZ_CHECK(info.max_codes == proto::kMaxCodes);
        FUZZ_CHECK(info.max_slots == flutterscan::kMaxSlots);
        FUZZ_CHECK(info.board_id == board_.board_id && info.build_id == board_.build_id);
        break;
      }
      case proto::Command::kGetStatus: {
        unchanged();
        const auto st = proto::decode_payload<proto::StatusReply>(payload).value();
        FUZZ_CHECK(same_status(st, controller_->status()));
        FUZZ_CHECK(st.uptime_us == port_.now_us());
        FUZZ_CHECK(st.state <= static_cast<std::uint8_t>(proto::ControllerState::kFault));
        FUZZ_CHECK(st.sync_mode <= static_cast<std::uint8_t>(proto::SyncMode::kFreeRun));
        FUZZ_CHECK(st.last_fault <= static_cast<std::uint8_t>(proto::FaultCode::kPort));
        FUZZ_CHECK((st.flags & ~0x0Fu) == 0);
        FUZZ_CHECK(st.active_code_id == proto::kNoCode || st.active_code_id < proto::kMaxCodes);
        FUZZ_CHECK(st.pending_code_id == proto::kNoCode || st.pending_code_id < proto::kMaxCodes);
        break;
      }
      case proto::Command::kSetCode: {
        const auto r = proto::decode_payload<proto::SetCodeRequest>(args).value();
        const auto rep = proto::decode_payload<proto::SetCodeReply>(payload).value();
        FUZZ_CHECK(rep.complete <= 1 && rep.reserved0 == 0);
        FUZZ_CHECK(rep.slots_received == r.first_slot + r.slot_count);
        FUZZ_CHECK(rep.slots_received <= r.total_slots);
        FUZZ_CHECK((rep.complete == 1) == (rep.slots_received == r.total_slots));
        if (rep.complete) {
          const auto& stored = controller_->settings().codes[r.code_id];
          FUZZ_CHECK(stored.present && stored.code.length() == r.total_slots &&
                     stored.code.leds() == r.led_count);
        }
        break;
      }
      case proto::Command::kSelectCode: {
        const auto r = proto::decode_payload<proto::SelectCodeRequest>(args).value();
        FUZZ_CHECK(controller_->settings().selected_code == r.code_id);
        FUZZ_CHECK(controller_->settings().codes[r.code_id].present);
        break;
      }
      case proto::Command::kArm:
        FUZZ_CHECK(state_before == proto::ControllerState::kIdle);
        FUZZ_CHECK(controller_->state() == proto::ControllerState::kArmed);
        break;
      case proto::Command::kDisarm:
      case proto::Command::kEnterBootloader:
        FUZZ_CHECK(controller_->state() == proto::ControllerState::kIdle);
        FUZZ_CHECK(port_.led_mask() == 0);
        FUZZ_CHECK(!port_.slot_table_running() && !port_.frame_timer_running());
        if (command == proto::Command::kEnterBootloader)
          FUZZ_CHECK(controller_->bootloader_requested());
        break;
      case proto::Command::kSelfTest: {
        const auto r = proto::decode_payload<proto::SelfTestRequest>(args).value();
        const auto rep = proto::decode_payload<proto::SelfTestReply>(payload).value();
        FUZZ_CHECK(rep.leds_stepped == board_.pins.led_count);
        FUZZ_CHECK(rep.duration_us ==
                   r.step_time_us * static_cast<std::uint32_t>(board_.pins.led_count));
        FUZZ_CHECK(port_.slot_table_running());
        break;
      }
      case proto::Command::kSaveConfig: {
        const auto rep = proto::decode_payload<proto::SaveConfigReply>(payload).value();
        FUZZ_CHECK(rep.bytes_written == sizeof(fw::ConfigImage));
        FUZZ_CHECK(same_settings(saved_settings(), controller_->settings()));
        break;
      }
      default:
        break;
    }
    return status;
  }

  /// load_config of the saved page, which must succeed. Decoding is a pure
  /// function of the page's bytes and the board, and its bitwise CRC over the
  /// 2 KiB image took a tenth of the time; so the settings of the last few
  /// pages decoded (for this board byte) are remembered and a page equal
  /// byte for byte to one of them reuses its settings.
  const fw::ControllerSettings& saved_settings() {
    struct Entry {
      int board = -1;
      std::array<std::uint8_t,
                 fw::kConfigCopies*(sizeof(fw::ConfigImage) + sizeof(fw::ConfigCommit))>
          bytes{};
      std::optional<fw::ControllerSettings> settings;
    };
    constexpr std::size_t kEntries = 8;
    static std::array<Entry, kEntries> cache;
    static std::size_t next_victim = 0;
    // Both copies (image and commit each) decide what loads.
    constexpr std::size_t kCopyBytes = sizeof(fw::ConfigImage) + sizeof(fw::ConfigCommit);
    std::array<std::uint8_t, fw::kConfigCopies * kCopyBytes> bytes{};
    for (int c = 0; c < fw::kConfigCopies; ++c) {
      const auto page = port_.flash_page(c);
      FUZZ_CHECK(page.size() >= kCopyBytes);
      std::memcpy(bytes.data() + static_cast<std::size_t>(c) * kCopyBytes, page.data(), kCopyBytes);
    }
    for (const Entry& e : cache)
      if (e.board == board_byte_ && e.bytes == bytes) return *e.settings;
    const auto loaded = fw::load_config(port_, board_);
    FUZZ_CHECK(loaded.ok());
    Entry& e = cache[next_victim];
    next_victim = (next_victim + 1) % kEntries;
    e.board = board_byte_;
    e.bytes = bytes;
    e.settings = loaded.value();
    return *e.settings;
  }

  void read_events(int count) {
    for (int i = 0; i < count; ++i) {
      std::array<std::uint8_t, proto::kReportSize> report;
      report.fill(0xA5);
      const std::size_t size = handler_->next_event_report(report);
      if (size == 0) return;
      FUZZ_CHECK(size == proto::kReportSize);
      check_event_report(report, false);
    }
  }

  /// An exposure event report (from read_events or the HID IN endpoint).
  void check_event_report(std::span<const std::uint8_t> report, bool via_usb) {
    const proto::MessageHeader h = proto::peek_header(report);
    FUZZ_CHECK(h.command == static_cast<std::uint8_t>(proto::Command::kExposureEvent));
    FUZZ_CHECK(h.status == 0);
    if (g_trace)
      std::fprintf(stderr, "event report sequence %u (%s)\n", h.sequence,
                   via_usb ? "HID IN endpoint" : "direct");
    // Two readers (read_events and the HID interface) take events from one
    // queue: each sees its sequences ascend, and no sequence comes twice.
    // The 8-bit sequence is numbered as reports are built, so a new one is
    // near the newest built so far (+1; the HID IN endpoint may deliver one
    // built a little earlier): unwrapped against that, a reader's sequences
    // ascend even when the other reader took 128 or more in between
    // (crashes/event-sequence-gap-over-128).
    const auto delta = static_cast<std::int8_t>(
        static_cast<std::uint8_t>(h.sequence - static_cast<std::uint8_t>(event_top_)));
    const std::int64_t sequence = event_top_ + delta;
    FUZZ_CHECK(sequence >= 0);
    std::int64_t& next = via_usb ? next_usb_event_ : next_direct_event_;
    FUZZ_CHECK(sequence >= next);
    next = sequence + 1;
    event_top_ = std::max(event_top_, sequence);
    FUZZ_CHECK(!events_seen_[h.sequence]);
    events_seen_.set(h.sequence);
    events_seen_.reset(static_cast<std::uint8_t>(h.sequence + 128));
    FUZZ_CHECK(h.payload_length == sizeof(proto::ExposureEvent));
    for (std::size_t k = proto::kHeaderSize + h.payload_length; k < proto::kReportSize; ++k)
      FUZZ_CHECK(report[k] == 0);
    const auto e =
        proto::decode_payload<proto::ExposureEvent>(
            std::span<const std::uint8_t>(report).subspan(proto::kHeaderSize, h.payload_length))
            .value();
    if (g_trace)
      std::fprintf(stderr, "%10llu us: event frame %u start %llu slot %u us flags 0x%x code %u\n",
                   static_cast<unsigned long long>(port_.now_us()), e.frame_counter,
                   static_cast<unsigned long long>(e.start_time_us), e.slot_time_us, e.flags,
                   e.code_id);
    FUZZ_CHECK(e.frame_counter >= 1);
    FUZZ_CHECK(e.slot_time_us >= proto::kMinSlotTimeUs && e.slot_time_us <= proto::kMaxSlotTimeUs);
    FUZZ_CHECK(e.start_time_us <= port_.now_us());
    FUZZ_CHECK((e.flags & ~0x1Fu) == 0);
    FUZZ_CHECK(e.code_id < proto::kMaxCodes);
    FUZZ_CHECK(e.slot_count >= 1 && e.slot_count <= flutterscan::kMaxSlots);
    FUZZ_CHECK(e.reserved0 == 0 && e.reserved1 == 0);
  }

  // Time -----------------------------------------------------------------------
  std::size_t work() const { return port_.led_transitions().size() + interposer_.callbacks; }
  bool exhausted() { return work() > kMaxWork || port_.now_us() >= kMaxVirtualUs; }

  void advance(std::uint64_t duration_us) {
    const std::uint64_t target = std::min(port_.now_us() + duration_us, kMaxVirtualUs);
    while (port_.now_us() < target && work() <= kMaxWork) {
      // Strobe-started work is bounded by kMaxStrobePulses; the frame timer's
      // is not, so it runs in steps of one frame at most. Steps in which no
      // event falls all see the same port and controller (check_state is
      // theirs alike) and the same LEDs on, whose on-time the last of them
      // checks longest: so a run of such steps is one jump to its last step.
      // (A 60 s advance with a 10 s frame period took 60,000 steps.)
      std::uint64_t next = target;
      if (port_.frame_timer_running()) {
        const std::uint64_t now = port_.now_us();
        const std::uint64_t event = port_.next_event_us();
        std::uint64_t step_end = now + kFrameStepUs;
        if (event > step_end) step_end = now + (event - 1 - now) / kFrameStepUs * kFrameStepUs;
        next = std::min(target, step_end);
      }
      port_.run_until(next);
      observe(guard_limits());
    }
  }

  // Invariants -------------------------------------------------------------------
  OnLimits guard_limits() const { return controller_->settings().guard.max_on_time_us; }
  static OnLimits min_limits(const OnLimits& a, const OnLimits& b) {
    OnLimits out{};
    for (std::size_t k = 0; k < out.size(); ++k) out[k] = std::min(a[k], b[k]);
    return out;
  }

  /// Checks the port against the controller's state, then the LED on-times of
  /// the writes since the last call, under `limits` (the guard in force).
  void observe(const OnLimits& limits) {
    check_state();
    check_ceiling();
    check_on_times(limits);
    check_duty();
  }

  /// The settings in force are within the compiled ceiling.
  void check_ceiling() const {
    const fw::ControllerSettings& s = controller_->settings();
    for (int led = 0; led < board_.pins.led_count; ++led) {
      const auto k = static_cast<std::size_t>(led);
      FUZZ_CHECK(s.guard.max_on_time_us[k] <= board_.ceiling.max_on_time_us[k]);
      FUZZ_CHECK(s.guard.max_duty_permille[k] <= board_.ceiling.max_duty_permille[k]);
      FUZZ_CHECK(s.brightness_permille[k] <= board_.ceiling.max_current_permille[k]);
      FUZZ_CHECK(port_.led_brightness(led) <= board_.ceiling.max_current_permille[k]);
    }
  }

  /// The duty oracle's state: the table playing (or last played) and the gap
  /// it followed; the LED record read so far.
  struct DutyState {
    bool have_start = false;  ///< a table started since the (power-on) boot
    bool have_gap = false;    ///< ... and one before it: its duty is checked
    std::uint64_t start_us = 0;
    std::uint64_t gap_us = 0;
    std::array<std::uint16_t, flutterscan::kMaxLeds> cap{};
    /// Energy so far, us x per mille of full current.
    std::array<std::uint64_t, flutterscan::kMaxLeds> energy{};
    std::uint8_t leds_on = 0;
    std::uint64_t last_us = 0;
    std::size_t seen_starts = 0;
    std::size_t seen_writes = 0;
  };

  /// Adds the LEDs' energy up to `t` (at the brightness they have now: it
  /// cannot rise while a table plays) to the current table's and checks it.
  void duty_accrue(std::uint64_t t) {
    DutyState& d = duty_;
    for (int led = 0; led < board_.pins.led_count; ++led) {
      const auto k = static_cast<std::size_t>(led);
      if (((d.leds_on >> led) & 1u) == 0) continue;
      d.energy[k] += (t - d.last_us) * port_.led_brightness(led);
      if (!d.have_gap || d.energy[k] <= static_cast<std::uint64_t>(d.cap[k]) * d.gap_us) continue;
      std::fprintf(stderr,
                   "LED %d: %llu us x per mille in the table started at %llu us, %llu us after "
                   "the one before: over max_duty_permille %u\n",
                   led, static_cast<unsigned long long>(d.energy[k]),
                   static_cast<unsigned long long>(d.start_us),
                   static_cast<unsigned long long>(d.gap_us), d.cap[k]);
      fail("an LED's energy duty exceeded the guard's max_duty_permille", __LINE__);
    }
    d.last_us = t;
  }

  /// A table start (or a boot) at `t`: the energy after it is judged over the gap since the last.
  void duty_start(std::uint64_t t) {
    DutyState& d = duty_;
    duty_accrue(std::max(d.last_us, t));
    d.have_gap = d.have_start;
    d.gap_us = t - d.start_us;
    d.have_start = true;
    d.start_us = t;
    d.energy = {};
    d.cap = controller_->settings().guard.max_duty_permille;
  }

  void check_duty() {
    DutyState& d = duty_;
    const auto& starts = port_.table_starts();
    const auto& writes = port_.led_transitions();
    while (d.seen_starts < starts.size() || d.seen_writes < writes.size()) {
      const bool start_next =
          d.seen_starts < starts.size() && (d.seen_writes == writes.size() ||
                                            starts[d.seen_starts] <= writes[d.seen_writes].time_us);
      if (start_next) {
        duty_start(starts[d.seen_starts++]);
      } else {
        const auto& w = writes[d.seen_writes++];
        duty_accrue(w.time_us);
        d.leds_on = w.led_mask;
      }
    }
    duty_accrue(std::max(d.last_us, port_.now_us()));
  }

  void check_state() const {
    // A callback on its way: the controller has not heard of the hardware yet.
    if (port_.callbacks_pending()) return;
    const proto::ControllerState state = controller_->state();
    const bool self_test = (controller_->status().flags & proto::kStatusSelfTestRunning) != 0;
    const bool exposing = state == proto::ControllerState::kExposing;
    const bool armed = state == proto::ControllerState::kArmed || exposing;
    if (self_test) FUZZ_CHECK(state == proto::ControllerState::kIdle);
    FUZZ_CHECK(port_.slot_table_running() == (exposing || self_test));
    FUZZ_CHECK(port_.frame_timer_running() ==
               (armed && controller_->settings().mode.sync != proto::SyncMode::kSlave));
    if (!exposing && !self_test) FUZZ_CHECK(port_.led_mask() == 0);
  }

  struct LedRun {
    bool on = false;
    std::uint64_t since_us = 0;
    std::uint32_t limit_us = 0;
    bool ever_off = false;
    std::uint64_t off_at_us = 0;      // the last off transition
    std::uint64_t prev_since_us = 0;  // start of the run that ended then
  };

  void check_run(int led, std::uint64_t start_us, std::uint64_t end_us,
                 std::uint32_t limit_us) const {
    const std::uint32_t ceiling = board_.ceiling.max_on_time_us[static_cast<std::size_t>(led)];
    if (end_us - start_us <= std::min(limit_us, ceiling)) return;
    std::fprintf(stderr,
                 "LED %d on from %llu us to %llu us (%llu us, runs less than %u us apart "
                 "joined), guard max_on_time_us %u, ceiling %u\n",
                 led, static_cast<unsigned long long>(start_us),
                 static_cast<unsigned long long>(end_us),
                 static_cast<unsigned long long>(end_us - start_us),
                 board_.ceiling.min_off_time_us, limit_us, ceiling);
    fail("an LED's joined run exceeded the guard's max_on_time_us or the ceiling", __LINE__);
  }

  void check_on_times(const OnLimits& limits) {
    const auto& writes = port_.led_transitions();
    const int leds = board_.pins.led_count;
    for (; seen_writes_ < writes.size(); ++seen_writes_) {
      const auto& w = writes[seen_writes_];
      for (int led = 0; led < leds; ++led) {
        LedRun& r = runs_[static_cast<std::size_t>(led)];
        const auto k = static_cast<std::size_t>(led);
        const bool on = ((w.led_mask >> led) & 1u) != 0;
        if (r.on) r.limit_us = std::min(r.limit_us, limits[k]);
        if (r.on && !on) {
          check_run(led, r.since_us, w.time_us, r.limit_us);
          r.on = false;
          r.ever_off = true;
          r.off_at_us = w.time_us;
          r.prev_since_us = r.since_us;
        } else if (!r.on && on) {
          // Off for less than the minimum off-time: one run (the die did not
          // cool), judged by the guard in force when it lights again: the host
          // may relax the guard in the gap (within the ceiling, which
          // check_run applies to every run), as the controller judges it.
          if (r.ever_off && w.time_us - r.off_at_us < board_.ceiling.min_off_time_us) {
            r.since_us = r.prev_since_us;
            r.limit_us = limits[k];
          } else {
            r.since_us = w.time_us;
            r.limit_us = limits[k];
          }
          r.on = true;
        }
      }
    }
    for (int led = 0; led < leds; ++led) {
      LedRun& r = runs_[static_cast<std::size_t>(led)];
      if (!r.on) continue;
      r.limit_us = std::min(r.limit_us, limits[static_cast<std::size_t>(led)]);
      check_run(led, r.since_us, port_.now_us(), r.limit_us);
    }
  }

  // The end ---------------------------------------------------------------------
  void finish() {
    const OnLimits before = guard_limits();
    std::array<std::uint8_t, proto::kReportSize> report{};
    FUZZ_CHECK(proto::encode_request(proto::Command::kDisarm, ++sequence_, report) ==
               proto::kReportSize);
    FUZZ_CHECK(feed_report(report) == proto::Status::kOk);
    observe(min_limits(before, guard_limits()));
    // Only strobe edges can still be pending, and a disarmed controller ignores them.
    port_.run_for(kSettleUs);
    observe(guard_limits());
    FUZZ_CHECK(port_.led_mask() == 0);
    const auto& writes = port_.led_transitions();
    FUZZ_CHECK(!writes.empty() && writes.back().led_mask == 0 && writes.back().pin_levels == 0);
    FUZZ_CHECK(!port_.slot_table_running() && !port_.frame_timer_running());
    for (const LedRun& r : runs_) FUZZ_CHECK(!r.on);
  }

  int board_byte_;  ///< the input's first byte, whence board_
  fw::BoardConfig board_;
  fw::sim::SimPort port_;
  std::optional<fw::Controller> controller_;
  std::optional<fw::CommandHandler> handler_;
  std::optional<fw::sim::SimUsbController> usb_;
  std::optional<fw::usb::ApplicationUsb> app_usb_;
  /// (command, sequence) of every request the HID OUT endpoint accepted and not yet answered.
  std::deque<std::array<std::uint8_t, 2>> pending_replies_;
  std::unique_ptr<DfuDevice> dfu_;
  Ep0Transfer app_ep0_;
  Ep0Transfer dfu_ep0_;
  Interposer interposer_;
  std::uint8_t sequence_ = 0;
  /// Event sequences unwrapped: the newest seen (-1: none since boot), and the
  /// next that read_events / the HID IN endpoint expects at least.
  std::int64_t event_top_ = -1;
  std::int64_t next_direct_event_ = 0;
  std::int64_t next_usb_event_ = 0;
  std::bitset<256> events_seen_;  ///< event sequences seen in the last 128
  int strobe_pulses_ = 0;
  std::size_t seen_writes_ = 0;
  std::array<LedRun, flutterscan::kMaxLeds> runs_{};
  DutyState duty_;
  std::uint64_t lock_us_ = 0;  ///< interrupt lock per request (product port timing)
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Reader in(std::span<const std::uint8_t>(data, size));
  // A fresh port and controller per input: SimPort has no exact reset (clock,
  // flash, recorded writes), and a fresh one keeps every input reproducible.
  Harness harness(in.u8());
  harness.run(in);
  return 0;
}
