// Writes the seed corpus of command_handler_fuzz into the directory given as
// argv[1]: host sessions made of valid requests (as the host library sends
// them), plus a few malformed ones, in the input format of fuzz_input.hpp.

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "flutterscan/common/protocol.hpp"
#include "fuzz_input.hpp"

namespace {

namespace proto = flutterscan::protocol;
using flutterscan::firmware::fuzz::InputWriter;
using flutterscan::firmware::fuzz::Op;
using Report = std::array<std::uint8_t, proto::kReportSize>;

// Board bytes (fuzz_input.hpp): 3 LEDs on pins 0..2 with the default guard,
// 1 LED, 4 LEDs on scattered pins with a permissive guard.
constexpr std::uint8_t kBoard3 = 0x02;
constexpr std::uint8_t kBoard1 = 0x00;
constexpr std::uint8_t kBoard4Permissive = 0x3B;

std::uint8_t g_sequence = 0;

template <typename T>
Report request(proto::Command command, const T& payload) {
  Report r{};
  proto::encode_request(command, ++g_sequence, payload, r);
  return r;
}

Report request(proto::Command command) {
  Report r{};
  proto::encode_request(command, ++g_sequence, r);
  return r;
}

/// SetCode chunks of a code given as per-slot masks, as raw reports.
void upload(InputWriter& w, std::uint8_t id, std::uint8_t leds,
            const std::vector<std::uint8_t>& masks, std::uint8_t flags = 0) {
  for (std::size_t first = 0; first < masks.size(); first += proto::kSlotsPerCodeChunk) {
    proto::SetCodeRequest r{};
    r.code_id = id;
    r.led_count = leds;
    r.total_slots = static_cast<std::uint16_t>(masks.size());
    r.first_slot = static_cast<std::uint16_t>(first);
    const std::size_t n = std::min(masks.size() - first, proto::kSlotsPerCodeChunk);
    r.slot_count = static_cast<std::uint8_t>(n);
    r.flags = flags;
    for (std::size_t i = 0; i < n; ++i) r.masks[i] = masks[first + i];
    w.raw_report(request(proto::Command::kSetCode, r));
  }
}

/// A one-LED code from a bit string.
std::vector<std::uint8_t> bits(const char* digits) {
  std::vector<std::uint8_t> out;
  for (const char* p = digits; *p; ++p) out.push_back(static_cast<std::uint8_t>(*p - '0'));
  return out;
}

/// A 52-slot one-LED flutter code.
std::vector<std::uint8_t> code52() {
  return bits("1010000111000001010000110011110111010111001001100111");
}

/// A 3-LED one-of-N code of `length` slots.
std::vector<std::uint8_t> rgb(std::size_t length) {
  std::vector<std::uint8_t> out;
  for (std::size_t i = 0; i < length; ++i)
    out.push_back(static_cast<std::uint8_t>(1u << ((i * 7 + i / 3) % 3)));
  return out;
}

void timing(InputWriter& w, std::uint32_t slot_us, std::uint32_t period_us,
            proto::SlotTimeSource source = proto::SlotTimeSource::kFixed) {
  w.raw_report(
      request(proto::Command::kSetTiming,
              proto::SetTimingRequest{slot_us, period_us, static_cast<std::uint8_t>(source), {}}));
}

void mode(InputWriter& w, proto::SyncMode sync, bool active_low = false) {
  w.raw_report(
      request(proto::Command::kSetMode,
              proto::SetModeRequest{
                  static_cast<std::uint8_t>(sync), static_cast<std::uint8_t>(active_low), {}}));
}

void select(InputWriter& w, std::uint8_t id) {
  w.raw_report(request(proto::Command::kSelectCode, proto::SelectCodeRequest{id, {}}));
}

void guard(InputWriter& w, std::uint32_t on_us, std::uint16_t duty) {
  proto::SetGuardRequest g{};
  g.max_on_time_us.fill(on_us);
  g.max_duty_permille.fill(duty);
  w.raw_report(request(proto::Command::kSetGuard, g));
}

bool write_bytes(const std::string& path, const std::vector<std::uint8_t>& d) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) {
    std::perror(path.c_str());
    return false;
  }
  const bool ok = std::fwrite(d.data(), 1, d.size(), f) == d.size();
  return std::fclose(f) == 0 && ok;
}

/// The seed as it is, and again with the product port's timing (board byte
/// bit 6; bit 7: slow interrupts): pre-armed tables, latency, the lock.
bool write(const std::string& dir, const char* name, const InputWriter& w) {
  std::vector<std::uint8_t> d(w.data().begin(), w.data().end());
  bool ok = write_bytes(dir + "/" + name, d);
  if (d.empty()) return ok;
  d[0] = static_cast<std::uint8_t>(d[0] | flutterscan::firmware::fuzz::kBoardTiming);
  ok &= write_bytes(dir + "/" + name + "_timed", d);
  d[0] = static_cast<std::uint8_t>(d[0] | flutterscan::firmware::fuzz::kBoardSlowInterrupts);
  ok &= write_bytes(dir + "/" + name + "_timed_slow", d);
  return ok;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s OUT_DIR\n", argv[0]);
    return 2;
  }
  const std::string dir = argv[1];
  bool ok = true;

  {  // Identity and status.
    InputWriter w(kBoard3);
    w.raw_report(request(proto::Command::kGetInfo));
    w.raw_report(request(proto::Command::kGetStatus));
    ok &= write(dir, "info_status", w);
  }
  {  // Slave mode: a 52-slot code, one strobe per frame, events read.
    InputWriter w(kBoard1);
    upload(w, 0, 1, code52());
    select(w, 0);
    timing(w, 100, 0);
    mode(w, proto::SyncMode::kSlave);
    w.raw_report(request(proto::Command::kArm));
    w.strobes(4, 100, 20'000, 6'000);
    w.advance(100'000);
    w.read_events(4);
    w.raw_report(request(proto::Command::kGetStatus));
    w.raw_report(request(proto::Command::kDisarm));
    ok &= write(dir, "slave_code52", w);
  }
  {  // Master mode, 3 LEDs, brightness.
    InputWriter w(kBoard3);
    upload(w, 1, 3, rgb(24), proto::kCodeFlagOneOfN);
    select(w, 1);
    timing(w, 50, 2'000);
    mode(w, proto::SyncMode::kMaster);
    w.raw_report(
        request(proto::Command::kSetBrightness, proto::SetBrightnessRequest{{1000, 500, 250, 0}}));
    w.raw_report(request(proto::Command::kArm));
    w.advance(10'000);
    w.read_events(5);
    w.raw_report(request(proto::Command::kDisarm));
    ok &= write(dir, "master_rgb", w);
  }
  {  // Free run with a code switch while armed.
    InputWriter w(kBoard4Permissive);
    upload(w, 2, 1, bits("1100101"));
    upload(w, 3, 1, bits("1011001"));
    select(w, 2);
    timing(w, 200, 1'400);
    mode(w, proto::SyncMode::kFreeRun);
    w.raw_report(request(proto::Command::kArm));
    w.advance(3'000);
    select(w, 3);
    w.advance(5'000);
    w.read_events(8);
    ok &= write(dir, "freerun_switch", w);
  }
  {  // Follow-exposure slot time in slave mode.
    InputWriter w(kBoard3);
    upload(w, 0, 2, {1, 2, 3, 0, 1, 2, 0, 3});
    select(w, 0);
    timing(w, 100, 0, proto::SlotTimeSource::kFollowExposure);
    guard(w, 50'000, 500);  // the product's ceiling
    w.raw_report(request(proto::Command::kArm));
    w.strobes(6, 10, 5'000, 2'400);
    w.op(Op::kEncoder).u8(1).i32(12'345);
    w.advance(40'000);
    w.read_events(6);
    ok &= write(dir, "slave_follow", w);
  }
  {  // A 200-slot code in four chunks.
    InputWriter w(kBoard3);
    std::vector<std::uint8_t> masks;
    for (int i = 0; i < 200; ++i) masks.push_back(static_cast<std::uint8_t>((i * 5 + 1) % 8));
    upload(w, 7, 3, masks);
    select(w, 7);
    timing(w, 10, 0);
    guard(w, 100'000, 500);
    w.raw_report(request(proto::Command::kArm));
    w.strobes(2, 0, 3'000, 1'000);
    w.advance(10'000);
    w.read_events(2);
    ok &= write(dir, "long_code", w);
  }
  {  // Self test, save, reboot from flash.
    InputWriter w(kBoard3);
    w.raw_report(request(proto::Command::kSelfTest, proto::SelfTestRequest{500}));
    w.advance(2'000);
    upload(w, 4, 1, code52());
    select(w, 4);
    w.raw_report(request(proto::Command::kSaveConfig));
    w.op(Op::kReboot).u8(0);
    w.raw_report(request(proto::Command::kGetStatus));
    w.op(Op::kReboot).u8(1);
    w.raw_report(request(proto::Command::kArm));
    ok &= write(dir, "selftest_save_reboot", w);
  }
  {  // The ceiling: a guard and a brightness above it, the brightness raised
     // while armed; a power-on reboot, then an exposure at once (heat at boot).
    InputWriter w(kBoard3);
    guard(w, 100'001, 500);
    guard(w, 100'000, 501);
    guard(w, 5'000, 300);
    proto::SetBrightnessRequest b{};
    b.permille = {1000, 1001, 500, 0};
    w.raw_report(request(proto::Command::kSetBrightness, b));
    b.permille = {400, 400, 400, 0};
    w.raw_report(request(proto::Command::kSetBrightness, b));
    upload(w, 0, 3, {1, 0, 0, 1, 2, 4});
    select(w, 0);
    timing(w, 500, 3'050);
    mode(w, proto::SyncMode::kFreeRun);
    w.raw_report(request(proto::Command::kSaveConfig));
    w.raw_report(request(proto::Command::kArm));
    w.advance(20'000);
    b.permille = {1000, 1000, 1000, 0};
    w.raw_report(request(proto::Command::kSetBrightness, b));
    w.advance(20'000);
    w.op(Op::kReboot).u8(0);
    w.raw_report(request(proto::Command::kArm));
    w.advance(20'000);
    w.read_events(8);
    ok &= write(dir, "ceiling_heat", w);
  }
  {  // Faults: slot timer failure, port fault, USB reset, bootloader.
    InputWriter w(kBoard3);
    upload(w, 0, 1, bits("1101"));
    select(w, 0);
    w.raw_report(request(proto::Command::kArm));
    w.op(Op::kPortFailures).u8(1);
    w.strobes(1, 0, 0, 500);
    w.advance(1'000);
    w.raw_report(request(proto::Command::kGetStatus));
    w.raw_report(request(proto::Command::kDisarm));
    w.op(Op::kPortFailures).u8(0);
    w.raw_report(request(proto::Command::kArm));
    w.op(Op::kPortFault);
    w.op(Op::kUsbReset);
    w.raw_report(request(proto::Command::kEnterBootloader,
                         proto::EnterBootloaderRequest{proto::kEnterBootloaderMagic}));
    w.op(Op::kPoll);
    ok &= write(dir, "faults_bootloader", w);
  }
  {  // Malformed requests: unknown command, short, bad header, wrong payload length.
    InputWriter w(kBoard3);
    Report unknown{};
    proto::encode_raw(0x42, 7, proto::Status::kOk, {}, unknown);
    w.raw_report(unknown);
    const std::array<std::uint8_t, 3> short_report{0x01, 0x02, 0x00};
    w.raw_report(short_report);
    Report bad_header = request(proto::Command::kGetInfo);
    bad_header[3] = 1;
    w.raw_report(bad_header);
    Report bad_length = request(proto::Command::kSetMode, proto::SetModeRequest{});
    bad_length[2] = 3;
    w.raw_report(bad_length);
    w.op(Op::kReport).u8(3).u8(9).u8(0).u8(0).u8(0).u8(0);
    ok &= write(dir, "malformed", w);
  }
  {  // USB: Linux's enumeration requests, then HID requests and replies, a halt, a reset.
    InputWriter w(kBoard3);
    w.op(Op::kBusReset);
    w.setup(0x80, 6, 0x0100, 0, 64);
    w.enumerate();
    w.setup(0x80, 6, 0x0200, 0, 9);
    w.setup(0x80, 6, 0x0200, 0, 59);
    w.setup(0x80, 6, 0x0303, 0x0409, 255);
    w.setup(0x21, 0x0A, 0, 0, 0);
    w.setup(0x81, 6, 0x2200, 0, 25);
    w.hid_out(request(proto::Command::kGetInfo));
    w.hid_out(request(proto::Command::kGetStatus));
    w.hid_in(2);
    w.setup(0x02, 3, 0, 0x81, 0);  // SET_FEATURE(ENDPOINT_HALT) on the IN endpoint
    w.hid_out(request(proto::Command::kGetStatus));
    w.hid_in(1);
    w.setup(0x02, 1, 0, 0x81, 0);
    w.hid_in(2);
    w.setup(0xA1, 3, 0, 1, 6);  // DFU runtime GETSTATUS
    w.op(Op::kBusReset);
    ok &= write(dir, "usb_enumerate_hid", w);
  }
  {  // USB: armed in free-run, events on the IN endpoint between replies, then DFU_DETACH.
    InputWriter w(kBoard4Permissive);
    w.enumerate();
    upload(w, 0, 3, code52());
    select(w, 0);
    w.raw_report(request(proto::Command::kSetTiming, proto::SetTimingRequest{100, 10'000, 0, {}}));
    w.raw_report(request(
        proto::Command::kSetMode,
        proto::SetModeRequest{static_cast<std::uint8_t>(proto::SyncMode::kFreeRun), 0, {}}));
    w.hid_out(request(proto::Command::kArm));
    w.advance(35'000);
    w.hid_out(request(proto::Command::kGetStatus));
    w.hid_in(8);
    w.setup(0x21, 0, 1000, 1, 0);  // DFU_DETACH
    w.hid_in(2);
    ok &= write(dir, "usb_events_detach", w);
  }
  {  // DFU mode: a good download, a corrupt one, then requests of every kind.
    InputWriter w(kBoard3);
    w.op(Op::kDfuDownload).u8(1).u16(9000).u8(0);
    w.op(Op::kDfuDownload).u8(2).u16(3000).u8(2);
    w.op(Op::kDfuSetup).u8(0x21).u8(4).u16(0).u16(0).u16(0);     // CLRSTATUS
    w.op(Op::kDfuSetup).u8(0xA1).u8(2).u16(0).u16(0).u16(1024);  // UPLOAD
    w.op(Op::kDfuSetup).u8(0x21).u8(6).u16(0).u16(0).u16(0);     // ABORT
    w.op(Op::kDfuDownload).u8(3).u16(5000).u8(4);
    ok &= write(dir, "dfu_sessions", w);
  }
  {  // Endpoint 0 packet by packet (kEp0Packets): the application's configuration
     // descriptor, SET_CONFIGURATION, back-to-back SETUPs; then in DFU mode an
     // UPLOAD read in 64-byte packets, a DNLOAD block whose OUT data stage a
     // SETUP interrupts, and a whole block of 16 packets with its status stage.
    auto setup = [](InputWriter& w, std::uint8_t type, std::uint8_t request, std::uint16_t value,
                    std::uint16_t index, std::uint16_t length) {
      w.u8(0).u8(type).u8(request).u16(value).u16(index).u16(length);
    };
    auto in = [](InputWriter& w, int n) {
      for (int i = 0; i < n; ++i) w.u8(2);
    };
    auto out = [](InputWriter& w, std::uint8_t length, std::uint8_t fill) {
      w.u8(1).u8(length);
      for (int i = 0; i < length; ++i) w.u8(static_cast<std::uint8_t>(fill + i));
    };
    InputWriter w(kBoard3);
    w.op(Op::kBusReset);
    w.op(Op::kEp0Packets).u8(0).u8(9 - 1);  // count - 1
    setup(w, 0x00, 5, 3, 0, 0);             // SET_ADDRESS 3
    in(w, 1);                               // its status stage
    setup(w, 0x80, 6, 0x0200, 0, 255);
    in(w, 2);
    out(w, 0, 0);  // status stage
    setup(w, 0x80, 6, 0x0100, 0, 18);
    setup(w, 0x00, 9, 1, 0, 0);  // right behind it: SET_CONFIGURATION 1
    in(w, 1);
    w.op(Op::kEp0Packets).u8(1).u8(18 - 1);
    setup(w, 0xA1, 2, 0, 0, 200);  // UPLOAD, 4 packets
    in(w, 4);
    out(w, 0, 0);
    setup(w, 0x21, 6, 0, 0, 0);  // ABORT
    in(w, 1);
    setup(w, 0x21, 1, 0, 0, 1024);  // DNLOAD block 0 ...
    for (int i = 0; i < 5; ++i) out(w, 64, static_cast<std::uint8_t>(i));
    setup(w, 0xA1, 3, 0, 0, 6);  // ... interrupted by GETSTATUS
    in(w, 1);
    out(w, 0, 0);
    setup(w, 0x21, 1, 0, 0, 1024);  // ... and now whole
    w.op(Op::kEp0Packets).u8(1).u8(17 - 1);
    for (int i = 0; i < 16; ++i) out(w, 64, static_cast<std::uint8_t>(i));
    in(w, 1);
    ok &= write(dir, "ep0_packets", w);
  }
  return ok ? 0 : 1;
}
