// hil_client: a small controller client for the HIL tests, built once per
// hidapi backend (hil_client_hidraw links flutterscan_device_hidraw,
// hil_client_libusb links flutterscan_device_libusb), so both backends are
// checked against the mocked device. Output is "key=value" lines for the tests.
//
//   hil_client info
//   hil_client session --code DIGITS --slot-us N --exposures N
//                      [--switch-code DIGITS --switch-after K] [--reply-timeout-ms N]
//   hil_client raw HEX [HEX ...]      (one request report per argument)
//   hil_client bad-args
//   hil_client wire HEX [HEX ...]     (hid_write of exactly these bytes, any length,
//                                      then the replies; then GetStatus through the client)
//
// Exit status: 0 success, 1 device failure (message on stderr), 2 bad usage.

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <string>
#include <thread>
#include <vector>

#include <hidapi/hidapi.h>

#include "device/controller_client.hpp"
#include "device/usb_discovery.hpp"

namespace {

using namespace flutterscan;
using device::ControllerClient;

int fail(const device::DeviceError& e, const char* what) {
  std::cerr << "hil_client: " << what << ": " << e.message << "\n";
  return 1;
}

device::Expected<std::unique_ptr<ControllerClient>> open_client(int reply_timeout_ms) {
  auto found = device::find_controllers();
  if (!found) return device::fail<std::unique_ptr<ControllerClient>>(found.error());
  std::cout << "found=" << found.value().size() << "\n";
  for (const auto& d : found.value())
    std::cout << "device mode=" << device::mode_name(d.mode) << " serial=" << d.serial
              << " release=" << std::hex << d.release << std::dec << " product=" << d.product
              << "\n";
  auto picked =
      device::pick_controller(found.value(), std::nullopt, device::DeviceMode::kApplication);
  if (!picked) return device::fail<std::unique_ptr<ControllerClient>>(picked.error());
  device::ClientOptions options;
  options.reply_timeout = std::chrono::milliseconds(reply_timeout_ms);
  options.reconnect = false;
  return ControllerClient::connect(device::hid_opener(picked.value().serial), options);
}

void print_info(const ControllerClient& client) {
  const protocol::InfoReply i = client.info();
  std::cout << "backend=" << FLUTTERSCAN_HIDAPI_BACKEND << "\n"
            << "link=" << client.description() << "\n"
            << "protocol=" << int{i.protocol_major} << "." << int{i.protocol_minor} << "\n"
            << "firmware=" << int{i.firmware_major} << "." << int{i.firmware_minor} << "."
            << int{i.firmware_patch} << "\n"
            << "board_id=" << i.board_id << "\n"
            << "led_count=" << int{i.led_count} << "\n"
            << "max_codes=" << int{i.max_codes} << "\n";
}

device::Expected<LedCode> parse_code(const std::string& digits, int leds) {
  auto code = LedCode::parse(digits, leds, CodeRule::kOneOfN);
  if (!code) return device::fail<LedCode>(device::ErrorKind::kBadInput, "bad code " + digits);
  return device::Expected<LedCode>::success(code.value());
}

int run_session(ControllerClient& client, const std::string& digits, std::uint32_t slot_us,
                int exposures, const std::string& switch_digits, int switch_after) {
  const int leds = client.info().led_count;
  auto code = parse_code(digits, leds);
  if (!code) return fail(code.error(), "code");
  if (auto r = client.set_code(0, code.value(), true); !r) return fail(r.error(), "set_code 0");
  if (!switch_digits.empty()) {
    auto second = parse_code(switch_digits, leds);
    if (!second) return fail(second.error(), "switch code");
    if (auto r = client.set_code(1, second.value(), true); !r) return fail(r.error(), "set_code 1");
  }
  if (auto r = client.select_code(0); !r) return fail(r.error(), "select_code 0");
  protocol::SetTimingRequest timing{};
  timing.slot_time_us = slot_us;
  timing.slot_time_source = static_cast<std::uint8_t>(protocol::SlotTimeSource::kFixed);
  if (auto r = client.set_timing(timing); !r) return fail(r.error(), "set_timing");
  if (auto r = client.set_mode(protocol::SyncMode::kSlave, false); !r)
    return fail(r.error(), "set_mode");
  if (auto r = client.arm(); !r) return fail(r.error(), "arm");
  std::cout << "armed\n";
  int received = 0;
  int missing = 0;
  while (received < exposures) {
    const auto notice = client.next_event(std::chrono::milliseconds(3000));
    if (!notice) {
      std::cerr << "hil_client: no exposure event within 3 s after " << received << " events\n";
      break;
    }
    const protocol::ExposureEvent& e = notice->event;
    ++received;
    missing += static_cast<int>(notice->frames_missing_before);
    std::cout << "event frame=" << e.frame_counter << " code=" << int{e.code_id}
              << " slot_us=" << e.slot_time_us << " slots=" << e.slot_count
              << " delta=" << e.encoder_delta << " start_us=" << e.start_time_us
              << " missing_before=" << notice->frames_missing_before << "\n";
    if (!switch_digits.empty() && received == switch_after) {
      if (auto r = client.select_code(1); !r) return fail(r.error(), "select_code 1");
      std::cout << "switched after=" << received << "\n";
    }
  }
  if (auto r = client.disarm(); !r) return fail(r.error(), "disarm");
  const auto stats = client.stats();
  std::cout << "events=" << received << "\nframes_missing=" << stats.frames_missing
            << "\nretries=" << stats.retries << "\n";
  return received == exposures ? 0 : 1;
}

bool parse_hex(const std::string& hex, std::vector<std::uint8_t>& out) {
  if (hex.size() % 2 != 0) return false;
  out.clear();
  for (std::size_t i = 0; i < hex.size(); i += 2) {
    unsigned v = 0;
    if (std::sscanf(hex.c_str() + i, "%2x", &v) != 1) return false;
    out.push_back(static_cast<std::uint8_t>(v));
  }
  return true;
}

int run_raw(ControllerClient& client, const std::vector<std::string>& reports) {
  for (const std::string& hex : reports) {
    std::vector<std::uint8_t> bytes;
    if (!parse_hex(hex == "-" ? std::string() : hex, bytes)) {
      std::cerr << "hil_client: raw " << hex << ": not hex bytes\n";
      return 2;
    }
    auto reply = client.exchange_raw(bytes);
    if (!reply) return fail(reply.error(), "raw");
    std::cout << "reply bytes=" << bytes.size() << " command=" << int{reply.value()[0]}
              << " status=" << int{reply.value()[3]} << "\n";
  }
  auto status = client.status();
  if (!status) return fail(status.error(), "status after raw reports");
  std::cout << "status_ok state=" << int{status.value().state} << "\n";
  return 0;
}

int run_bad_args(ControllerClient& client) {
  auto report = [](const char* what, const device::Expected<device::Done>& r) {
    std::cout << what << "=" << (r ? 0 : static_cast<int>(r.error().status)) << " "
              << (r ? "" : r.error().message) << "\n";
  };
  protocol::SetTimingRequest timing{};
  timing.slot_time_us = 0;
  report("slot_time_0", client.set_timing(timing));
  timing.slot_time_us = protocol::kMaxSlotTimeUs + 1;
  report("slot_time_too_long", client.set_timing(timing));
  auto sel = client.select_code(protocol::kMaxCodes);
  std::cout << "select_code_out_of_range=" << (sel ? 0 : static_cast<int>(sel.error().status))
            << "\n";
  auto sel_empty = client.select_code(5);
  std::cout << "select_code_empty=" << (sel_empty ? 0 : static_cast<int>(sel_empty.error().status))
            << "\n";
  protocol::SetBrightnessRequest b{};
  b.permille[0] = protocol::kBrightnessFullScale + 1;
  auto br = client.set_brightness(b);
  std::cout << "brightness_too_high=" << (br ? 0 : static_cast<int>(br.error().status)) << "\n";
  report("arm_without_code", client.arm());
  auto status = client.status();
  if (!status) return fail(status.error(), "status after bad arguments");
  std::cout << "status_ok state=" << int{status.value().state} << "\n";
  return 0;
}

/// Writes each report exactly as given (hidapi adds nothing but the report id 0),
/// then prints the replies that come back within 300 ms.
int run_wire(const std::vector<std::string>& reports) {
  if (hid_init() != 0) {
    std::cerr << "hil_client: hid_init failed\n";
    return 1;
  }
  hid_device* dev = hid_open(protocol::kUsbVendorId, protocol::kUsbProductIdApplication, nullptr);
  if (dev == nullptr) {
    std::cerr << "hil_client: hid_open failed\n";
    return 1;
  }
  for (const std::string& hex : reports) {
    std::vector<std::uint8_t> bytes;
    if (!parse_hex(hex == "-" ? std::string() : hex, bytes)) {
      std::cerr << "hil_client: wire " << hex << ": not hex bytes\n";
      hid_close(dev);
      return 2;
    }
    bytes.insert(bytes.begin(), 0);  // report id: none
    const int written = hid_write(dev, bytes.data(), bytes.size());
    std::cout << "wrote bytes=" << bytes.size() - 1 << " result=" << written << "\n";
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(300);
    while (std::chrono::steady_clock::now() < deadline) {
      std::array<unsigned char, 64> in{};
      const int n = hid_read_timeout(dev, in.data(), in.size(), 5);
      if (n < 0) break;
      if (n == 0) {
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
        continue;
      }
      std::cout << "wire_reply command=" << int{in[0]} << " status=" << int{in[3]} << "\n";
    }
  }
  hid_close(dev);
  hid_exit();
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"hil_client: controller client for the HIL tests (hidapi backend " +
               std::string(FLUTTERSCAN_HIDAPI_BACKEND) + ")"};
  app.require_subcommand(1);
  int reply_timeout_ms = 500;
  app.add_option("--reply-timeout-ms", reply_timeout_ms, "Wait for one reply");
  auto* info = app.add_subcommand("info", "List controllers, connect, print GetInfo");
  auto* session = app.add_subcommand("session", "Code, timing, arm, collect events, disarm");
  std::string digits, switch_digits;
  std::uint32_t slot_us = 100;
  int exposures = 1, switch_after = 0;
  session->add_option("--code", digits, "Code digits (one of N)")->required();
  session->add_option("--slot-us", slot_us, "Slot time");
  session->add_option("--exposures", exposures, "Events to wait for");
  session->add_option("--switch-code", switch_digits, "Second code, selected while armed");
  session->add_option("--switch-after", switch_after, "Select the second code after K events");
  auto* raw = app.add_subcommand("raw", "Send raw request reports, then GetStatus");
  std::vector<std::string> reports;
  raw->add_option("reports", reports, "Hex bytes of each report ('-': empty)")->required();
  auto* bad = app.add_subcommand("bad-args", "Out-of-range arguments, then GetStatus");
  auto* wire = app.add_subcommand("wire", "hid_write raw bytes of any length, then GetStatus");
  std::vector<std::string> wire_reports;
  wire->add_option("reports", wire_reports, "Hex bytes of each write ('-': empty)")->required();
  CLI11_PARSE(app, argc, argv);

  if (wire->parsed()) {
    if (const int rc = run_wire(wire_reports); rc != 0) return rc;
  }

  auto client = open_client(reply_timeout_ms);
  if (!client) return fail(client.error(), "connect");
  print_info(*client.value());
  if (info->parsed()) return 0;
  if (session->parsed())
    return run_session(*client.value(), digits, slot_us, exposures, switch_digits, switch_after);
  if (raw->parsed()) return run_raw(*client.value(), reports);
  if (bad->parsed()) return run_bad_args(*client.value());
  if (wire->parsed()) {
    auto status = client.value()->status();
    if (!status) return fail(status.error(), "status after raw writes");
    std::cout << "status_ok state=" << int{status.value().state} << "\n";
    return 0;
  }
  return 2;
}
