// hil_harness: serves the firmware's own USB core (port/sim's SimBoard) to a
// program under test through a umockdev testbed, then writes what the board
// saw and did as JSON.
//
//   umockdev-wrapper hil_harness [options] -- flutterscan device info
//
// (Started without the umockdev preload library, it re-runs itself under
// umockdev-wrapper.) Exit status: the program's, 77 if umockdev cannot run
// here, 2 on bad usage, 124 if the program ran past --timeout-s.

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <string>
#include <thread>
#include <vector>

#include "board_host.hpp"
#include "flutterscan/common/image_header.hpp"
#include "mock_usb_bus.hpp"

namespace {

using namespace flutterscan;

constexpr int kSkip = 77;

bool preloaded() {
  const char* p = std::getenv("LD_PRELOAD");
  return p != nullptr && std::strstr(p, "libumockdev-preload") != nullptr;
}

/// Re-runs this program under umockdev-wrapper; returns only if that is impossible.
void reexec_wrapped(char** argv) {
  // The preload library comes before the sanitizer runtime in sanitizer builds,
  // which ASan refuses by default (the programs under test inherit this too).
  std::string asan = std::getenv("ASAN_OPTIONS") ? std::getenv("ASAN_OPTIONS") : "";
  if (asan.find("verify_asan_link_order") == std::string::npos) {
    asan += std::string(asan.empty() ? "" : ":") + "verify_asan_link_order=0";
    setenv("ASAN_OPTIONS", asan.c_str(), 1);
  }
  std::vector<char*> args;
  static char wrapper[] = "umockdev-wrapper";
  args.push_back(wrapper);
  for (char** a = argv; *a != nullptr; ++a) args.push_back(*a);
  args.push_back(nullptr);
  execvp(wrapper, args.data());
  std::cerr << "hil_harness: SKIP: cannot run umockdev-wrapper (" << std::strerror(errno)
            << "): the HIL tests need umockdev (tools/install-deps installs it)\n";
}

std::vector<std::uint8_t> read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw CLI::ValidationError("--image", path + ": cannot be read");
  return {std::istreambuf_iterator<char>(in), {}};
}

bool parse_unique_id(const std::string& hex, std::array<std::uint8_t, 12>& out) {
  if (hex.size() != 24) return false;
  for (std::size_t i = 0; i < 12; ++i) {
    unsigned v = 0;
    if (std::sscanf(hex.c_str() + 2 * i, "%2x", &v) != 1) return false;
    out[i] = static_cast<std::uint8_t>(v);
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"hil_harness: the controller's firmware USB core behind a umockdev testbed"};
  hil::Scenario scenario;
  std::string record_path;
  std::string image_path;
  std::string serial;
  std::string version = std::to_string(FLUTTERSCAN_VERSION_MAJOR) + "." +
                        std::to_string(FLUTTERSCAN_VERSION_MINOR) + "." +
                        std::to_string(FLUTTERSCAN_VERSION_PATCH);
  bool empty_flash = false;
  bool dfu_at_start = false;
  bool hangs_before_usb = false;
  double timeout_s = 60;
  std::vector<std::string> command;
  app.add_option("--record", record_path, "Write the board's records here as JSON");
  app.add_option("--image", image_path,
                 "Application image (.bin) in flash at power-on (default: a generated one)");
  app.add_option("--firmware-version", version,
                 "Version of the generated image in flash (MAJOR.MINOR.PATCH)");
  app.add_flag("--empty-flash", empty_flash,
               "No application in flash: the board stays in DFU mode");
  app.add_flag("--dfu", dfu_at_start, "Power on in DFU mode (as if the application asked for it)");
  app.add_flag("--hangs-before-usb", hangs_before_usb,
               "The image in flash hangs before USB (never confirms): watchdog resets at power-on "
               "until the bootloader keeps DFU mode");
  app.add_option("--serial", serial, "The chip's unique ID as 24 hex digits (the serial number)");
  app.add_option("--strobes", scenario.strobes_after_arm,
                 "Strobe pulses after the first successful Arm reply");
  app.add_option("--strobe-width-us", scenario.strobe_width_us, "Strobe pulse width");
  app.add_option("--strobe-period-us", scenario.strobe_period_us, "Time between strobes");
  app.add_option("--encoder-in-exposure", scenario.encoder_in_exposure,
                 "Encoder counts added early in exposure i: this + i");
  app.add_option("--encoder-between", scenario.encoder_between,
                 "Encoder counts added between exposures");
  app.add_option("--unresponsive-after", scenario.unresponsive_after,
                 "Stop answering after this many request reports");
  app.add_option("--unplug-after", scenario.unplug_after, "Unplug after this many request reports");
  app.add_option("--unplug-after-events", scenario.unplug_after_events,
                 "Unplug after this many exposure events reached the host");
  app.add_option("--unplug-at-block", scenario.unplug_at_block,
                 "Cut the power when DFU DNLOAD block N arrives");
  app.add_option("--replug-after-ms", scenario.replug_after_ms,
                 "Plug back in (power cycle) this long after an unplug");
  app.add_option("--recovery-pin-boots", scenario.recovery_pin_boots,
                 "The recovery pin (PB2) is held at power-on and through this many boots in "
                 "all (resets the board makes itself included), then released")
      ->check(CLI::Range(0, 100));
  app.add_option("--protocol-major", scenario.protocol_major,
                 "Protocol major GetInfo reports (to test the host's refusal)");
  app.add_option("--timeout-s", timeout_s, "Kill the program after this long");
  app.add_option("command", command, "The program to run inside the testbed (after --)")
      ->required();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }

  if (!preloaded()) {
    reexec_wrapped(argv);
    return kSkip;
  }

  firmware::sim::SimBoardConfig config;
  if (!serial.empty() && !parse_unique_id(serial, config.unique_id)) {
    std::cerr << "hil_harness: --serial " << serial << ": expected 24 hex digits\n";
    return 2;
  }
  std::vector<std::uint8_t> image;
  try {
    if (!image_path.empty()) {
      image = read_file(image_path);
    } else if (!empty_flash) {
      int major = 0, minor = 0, patch = 0;
      if (std::sscanf(version.c_str(), "%d.%d.%d", &major, &minor, &patch) != 3) {
        std::cerr << "hil_harness: --firmware-version " << version
                  << ": expected MAJOR.MINOR.PATCH\n";
        return 2;
      }
      image = firmware::sim::make_application_image(
          config.region.board_id, static_cast<std::uint8_t>(major),
          static_cast<std::uint8_t>(minor), static_cast<std::uint8_t>(patch), 16 * 1024);
    }
  } catch (const CLI::ValidationError& e) {
    std::cerr << "hil_harness: " << e.what() << "\n";
    return 2;
  }

  hil::BoardHost host(config, image, scenario);
  if (dfu_at_start) host.power_cycle(true);
  if (hangs_before_usb) host.hang_before_usb(10);
  hil::MockUsbBus bus(host);
  if (!bus.ok()) {
    std::cerr << "hil_harness: SKIP: umockdev could not create a testbed here\n";
    return kSkip;
  }
  if (!bus.sync()) return 1;

  const pid_t child = fork();
  if (child < 0) {
    std::cerr << "hil_harness: fork: " << std::strerror(errno) << "\n";
    return 1;
  }
  if (child == 0) {
    std::vector<char*> args;
    for (std::string& a : command) args.push_back(a.data());
    args.push_back(nullptr);
    execvp(args[0], args.data());
    std::cerr << "hil_harness: " << command[0] << ": " << std::strerror(errno) << "\n";
    _exit(127);
  }

  const auto deadline = std::chrono::steady_clock::now() +
                        std::chrono::milliseconds(static_cast<long>(timeout_s * 1000));
  int status = 0;
  bool timed_out = false;
  bool enumeration_failed = false;
  for (;;) {
    host.tick();
    if (!bus.sync()) enumeration_failed = true;
    const pid_t done = waitpid(child, &status, WNOHANG);
    if (done == child) break;
    if (std::chrono::steady_clock::now() > deadline) {
      timed_out = true;
      kill(child, SIGKILL);
      waitpid(child, &status, 0);
      break;
    }
    std::this_thread::sleep_for(std::chrono::microseconds(500));
  }
  // Let the board finish what is under way (an exposure, a bootloader hand-off).
  for (int i = 0; i < 20; ++i) {
    host.tick();
    bus.sync();
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }

  int exit_code = 1;
  nlohmann::json child_record;
  if (WIFEXITED(status)) {
    exit_code = WEXITSTATUS(status);
    child_record["exit_code"] = exit_code;
  } else if (WIFSIGNALED(status)) {
    child_record["signal"] = WTERMSIG(status);
    exit_code = 128 + WTERMSIG(status);
  }
  child_record["timed_out"] = timed_out;
  if (timed_out) {
    std::cerr << "hil_harness: " << command[0] << " still running after " << timeout_s
              << " s: killed\n";
    exit_code = 124;
  }
  if (!record_path.empty()) {
    nlohmann::json j = host.records();
    j["program"] = child_record;
    j["enumeration_failed"] = enumeration_failed;
    const std::string tmp = record_path + ".tmp";
    {
      std::ofstream out(tmp);
      out << j.dump(1) << "\n";
      if (!out) {
        std::cerr << "hil_harness: " << record_path << ": cannot be written\n";
        return 1;
      }
    }
    std::rename(tmp.c_str(), record_path.c_str());
  }
  return enumeration_failed && exit_code == 0 ? 1 : exit_code;
}
