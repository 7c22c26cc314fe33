// The QEMU test (CTest label `qemu`): boots the real fw-qemu ARM image on QEMU's
// netduinoplus2, talks to its USART1 console (version, selftest, expose, an
// unknown command, status) and checks, from QEMU's `-d unimp` log of GPIOA
// BSRR writes, that the LED bank followed the self test and the code slot by
// slot: per slot one LED set and the others reset, all off after the last.
//
// Usage: qemu_boot_test --elf FW.elf --work-dir DIR [--qemu qemu-system-arm]
//                       [--code DIGITS] [--slot-us N] [--timeout-s N]
// Exit 0 pass, 1 fail, 77 skip (no image, no qemu-system-arm, QEMU cannot start).
// Host only (POSIX: fork, exec, pipes, poll).

#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "flutterscan/common/protocol.hpp"
#include "flutterscan/firmware/qemu/qemu_board.hpp"

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

constexpr int kSkip = 77;
/// The seed's max-min triplet (docs/codes.md), the default code.
constexpr const char* kDefaultCode = "2212441414112412441224111241244244242212442211444144";

struct Options {
  std::string elf;
  std::string work_dir = ".";
  std::string qemu = "qemu-system-arm";
  std::string code = kDefaultCode;
  std::uint32_t slot_us = 100;
  int timeout_s = 20;
};

[[noreturn]] void skip(const std::string& why) {
  std::cout << "SKIP: " << why << "\n";
  std::exit(kSkip);
}

/// The first executable `name` on PATH (or `name` itself if it has a slash).
std::optional<std::string> find_program(const std::string& name) {
  if (name.find('/') != std::string::npos)
    return access(name.c_str(), X_OK) == 0 ? std::optional(name) : std::nullopt;
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path != nullptr ? path : "/usr/bin:/bin");
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    const std::string candidate = (dir.empty() ? "." : dir) + "/" + name;
    if (access(candidate.c_str(), X_OK) == 0) return candidate;
  }
  return std::nullopt;
}

/// QEMU as a child process with its serial console on a pair of pipes.
class QemuProcess {
 public:
  QemuProcess(const std::vector<std::string>& argv, const std::string& stderr_path) {
    int to_child[2];
    int from_child[2];
    if (pipe(to_child) != 0 || pipe(from_child) != 0) skip("cannot create pipes");
    pid_ = fork();
    if (pid_ < 0) skip("cannot fork");
    if (pid_ == 0) {
      prctl(PR_SET_PDEATHSIG, SIGKILL);  // never outlive the test
      dup2(to_child[0], STDIN_FILENO);
      dup2(from_child[1], STDOUT_FILENO);
      std::FILE* err = std::fopen(stderr_path.c_str(), "w");
      if (err != nullptr) dup2(fileno(err), STDERR_FILENO);
      close(to_child[1]);
      close(from_child[0]);
      std::vector<char*> args;
      for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
      args.push_back(nullptr);
      execv(args[0], args.data());
      _exit(127);
    }
    close(to_child[0]);
    close(from_child[1]);
    in_ = to_child[1];
    out_ = from_child[0];
    signal(SIGPIPE, SIG_IGN);
  }
  ~QemuProcess() { stop(); }

  bool send(const std::string& line) {
    const std::string data = line + "\n";
    return write(in_, data.data(), data.size()) == static_cast<ssize_t>(data.size());
  }

  /// The next console line, or nullopt at EOF or the deadline.
  std::optional<std::string> read_line(Clock::time_point deadline) {
    for (;;) {
      const auto newline = buffer_.find('\n');
      if (newline != std::string::npos) {
        std::string line = buffer_.substr(0, newline);
        buffer_.erase(0, newline + 1);
        if (!line.empty() && line.back() == '\r') line.pop_back();
        transcript_ += line + "\n";
        return line;
      }
      const auto left =
          std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
      if (left <= 0) return std::nullopt;
      pollfd fd{out_, POLLIN, 0};
      if (poll(&fd, 1, static_cast<int>(left)) <= 0) continue;
      char chunk[512];
      const ssize_t n = read(out_, chunk, sizeof chunk);
      if (n <= 0) return std::nullopt;  // QEMU exited
      buffer_.append(chunk, static_cast<std::size_t>(n));
    }
  }

  /// Stops QEMU (SIGTERM, then SIGKILL after 5 s); returns its wait status, -1 if unknown.
  int stop() {
    if (pid_ <= 0) return status_;
    if (in_ >= 0) close(in_);
    in_ = -1;
    int status = 0;
    if (waitpid(pid_, &status, WNOHANG) == 0) {
      kill(pid_, SIGTERM);
      const auto give_up = Clock::now() + std::chrono::seconds(5);
      while (waitpid(pid_, &status, WNOHANG) == 0) {
        if (Clock::now() > give_up) {
          kill(pid_, SIGKILL);
          waitpid(pid_, &status, 0);
          break;
        }
        usleep(10'000);
      }
    }
    status_ = status;
    pid_ = -1;
    if (out_ >= 0) close(out_);
    out_ = -1;
    return status_;
  }

  const std::string& transcript() const { return transcript_; }

 private:
  pid_t pid_ = -1;
  int in_ = -1;
  int out_ = -1;
  int status_ = -1;
  std::string buffer_;
  std::string transcript_;
};

std::string read_file(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

/// Every GPIOA BSRR write in QEMU's `-d unimp` log, in order. QEMU 7.2 writes
/// "GPIOA: unimplemented device write (size 4, offset 0x018, value 0x...)".
std::vector<std::uint32_t> bsrr_writes(const std::string& log) {
  std::vector<std::uint32_t> values;
  std::stringstream lines(log);
  std::string line;
  while (std::getline(lines, line)) {
    if (line.rfind("GPIOA: unimplemented device write", 0) != 0) continue;
    unsigned size = 0;
    unsigned long long offset = 0;
    unsigned long long value = 0;
    if (std::sscanf(line.c_str(),
                    "GPIOA: unimplemented device write (size %u, offset 0x%llx, value 0x%llx)",
                    &size, &offset, &value) == 3 &&
        size == 4 && offset == 0x18)
      values.push_back(static_cast<std::uint32_t>(value));
  }
  return values;
}

/// The number after `key` in a "key value key value" reply line.
std::optional<long long> field(const std::string& line, const std::string& key) {
  std::stringstream words(line);
  std::string word;
  while (words >> word) {
    if (word != key) continue;
    long long value = 0;
    if (words >> value) return value;
    return std::nullopt;
  }
  return std::nullopt;
}

class Checker {
 public:
  void expect(bool ok, const std::string& what) {
    if (!ok) {
      std::cout << "FAIL: " << what << "\n";
      ++failures_;
    }
  }
  int failures() const { return failures_; }

 private:
  int failures_ = 0;
};

/// The BSRR word that lights exactly the LEDs in `mask` and turns the others off
/// (written here from RM0090 8.4.7, independently of common/sequencer).
std::uint32_t expected_word(unsigned mask, const flutterscan::LedPinMap& pins) {
  std::uint32_t word = 0;
  for (int led = 0; led < pins.led_count; ++led) {
    const unsigned pin = pins.pins[static_cast<std::size_t>(led)];
    word |= (mask >> led) & 1u ? (1u << pin) : (1u << (16 + pin));
  }
  return word;
}

/// Checks `masks.size() + 1` writes from `first`: slot i lights masks[i], then all off;
/// also replays the pin levels to check which LEDs were on in each slot.
void check_sequence(Checker& check, const std::string& name,
                    const std::vector<std::uint32_t>& writes, long long first,
                    const std::vector<unsigned>& masks, const flutterscan::LedPinMap& pins) {
  const auto words = static_cast<long long>(masks.size()) + 1;
  if (first < 0 || first + words > static_cast<long long>(writes.size())) {
    check.expect(false, name + ": the log holds " + std::to_string(writes.size()) +
                            " BSRR writes, not the " + std::to_string(words) + " from write " +
                            std::to_string(first));
    return;
  }
  std::uint32_t levels = 0;
  for (long long i = 0; i < first + words; ++i) {
    const std::uint32_t w = writes[static_cast<std::size_t>(i)];
    levels = (levels & ~(w >> 16)) | (w & 0xFFFFu);  // set wins over reset
    if (i < first) continue;
    const auto slot = static_cast<std::size_t>(i - first);
    const unsigned mask = slot < masks.size() ? masks[slot] : 0u;
    unsigned on = 0;
    for (int led = 0; led < pins.led_count; ++led)
      if ((levels >> pins.pins[static_cast<std::size_t>(led)]) & 1u) on |= 1u << led;
    char text[160];
    std::snprintf(text, sizeof text,
                  "%s slot %zu: BSRR 0x%08x (want 0x%08x), LEDs on 0x%x (want 0x%x)", name.c_str(),
                  slot, w, expected_word(mask, pins), on, mask);
    check.expect(w == expected_word(mask, pins) && on == mask, text);
  }
}

Options parse_options(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const bool has_value = i + 1 < argc;
    if (arg == "--elf" && has_value)
      o.elf = argv[++i];
    else if (arg == "--work-dir" && has_value)
      o.work_dir = argv[++i];
    else if (arg == "--qemu" && has_value)
      o.qemu = argv[++i];
    else if (arg == "--code" && has_value)
      o.code = argv[++i];
    else if (arg == "--slot-us" && has_value)
      o.slot_us = static_cast<std::uint32_t>(std::stoul(argv[++i]));
    else if (arg == "--timeout-s" && has_value)
      o.timeout_s = std::stoi(argv[++i]);
    else {
      std::cerr << "usage: qemu_boot_test --elf FW.elf --work-dir DIR [--qemu BIN] [--code DIGITS]"
                   " [--slot-us N] [--timeout-s N]\n";
      std::exit(2);
    }
  }
  if (o.elf.empty()) {
    std::cerr << "qemu_boot_test: --elf is required\n";
    std::exit(2);
  }
  return o;
}

}  // namespace

int main(int argc, char** argv) {
  const Options options = parse_options(argc, argv);
  namespace board = flutterscan::firmware::qemu;
  constexpr flutterscan::firmware::BoardConfig kBoard = board::qemu_board_config();

  if (!fs::exists(options.elf))
    skip("fw-qemu image " + options.elf + " not built: run `make fw-qemu` (or `make test`)");
  const auto qemu = find_program(options.qemu);
  if (!qemu) skip(options.qemu + " not found: install it with tools/install-deps");

  std::vector<unsigned> code;
  for (const char c : options.code) {
    if (c != '1' && c != '2' && c != '4') {
      std::cerr << "qemu_boot_test: --code must be one-of-3 digits (1, 2, 4)\n";
      return 2;
    }
    code.push_back(static_cast<unsigned>(c - '0'));
  }

  fs::create_directories(options.work_dir);
  const std::string log_path = options.work_dir + "/unimp.log";
  const std::string stderr_path = options.work_dir + "/qemu.stderr";
  fs::remove(log_path);
  const std::vector<std::string> argv_qemu = {*qemu,        "-M",      "netduinoplus2",
                                              "-nographic", "-kernel", options.elf,
                                              "-serial",    "stdio",   "-monitor",
                                              "none",       "-icount", "shift=3,sleep=off",
                                              "-d",         "unimp",   "-D",
                                              log_path};
  std::cout << "running:";
  for (const auto& a : argv_qemu) std::cout << " " << a;
  std::cout << "\n";

  const auto deadline = Clock::now() + std::chrono::seconds(options.timeout_s);
  QemuProcess process(argv_qemu, stderr_path);
  Checker check;

  // Boot banner. No banner: QEMU could not start (skip) or the image is broken (fail).
  bool ready = false;
  while (auto line = process.read_line(deadline)) {
    if (line->find("ready") != std::string::npos) {
      ready = true;
      break;
    }
  }
  if (!ready) {
    const int status = process.stop();
    const std::string err = read_file(stderr_path);
    const bool exited = status >= 0 && WIFEXITED(status);
    std::cout << "console:\n" << process.transcript() << "qemu stderr:\n" << err << "\n";
    if (exited && WEXITSTATUS(status) != 0)
      skip(*qemu + " could not start (exit " + std::to_string(WEXITSTATUS(status)) + ")");
    std::cout << "FAIL: no boot banner from the firmware within " << options.timeout_s << " s\n";
    return 1;
  }

  auto ask = [&](const std::string& command) -> std::string {
    std::cout << "> " << command << "\n";
    if (!process.send(command)) return {};
    auto reply = process.read_line(deadline);
    std::cout << "< " << (reply ? *reply : std::string("(no reply)")) << "\n";
    return reply.value_or("");
  };

  // version: the firmware's and the protocol's, as this build knows them.
  const std::string version = ask("version");
  {
    std::ostringstream want;
    want << "version firmware " << int{kBoard.firmware_major} << "." << int{kBoard.firmware_minor}
         << "." << int{kBoard.firmware_patch} << " protocol "
         << int{flutterscan::protocol::kProtocolMajor} << "."
         << int{flutterscan::protocol::kProtocolMinor} << " board " << kBoard.board_id << " leds "
         << kBoard.pins.led_count;
    check.expect(version.rfind(want.str(), 0) == 0,
                 "version reply '" + version + "', want '" + want.str() + " ...'");
  }

  // The thermal guard counts the LEDs hot at every boot (their supply is not
  // the MCU's): nothing lights within the minimum off-time of boot, and the
  // duty counts from boot. Let 10 ms of virtual time pass since boot.
  const auto uptime = [&] { return field(ask("status"), "uptime_us").value_or(-1); };
  {
    long long now = uptime();
    for (int i = 0; i < 5000 && now >= 0 && now < 10'000; ++i) now = uptime();
    check.expect(now >= 10'000, "virtual time did not reach 10 ms after boot");
  }

  // selftest: each LED for 1 ms in turn.
  const std::string selftest = ask("selftest 1000");
  check.expect(selftest.rfind("selftest ok", 0) == 0 &&
                   field(selftest, "leds") == kBoard.pins.led_count &&
                   field(selftest, "writes") == kBoard.pins.led_count + 1,
               "selftest reply '" + selftest + "'");

  // The thermal guard counts the self test as an exposure (issue 15): the
  // code's duty is measured from the self test's start, so let 10 ms of
  // virtual time pass (status replies carry the clock; they write no LEDs).
  {
    const long long since = uptime();
    long long now = since;
    for (int i = 0; i < 5000 && since >= 0 && now >= 0 && now < since + 10'000; ++i) now = uptime();
    check.expect(since >= 0 && now >= since + 10'000,
                 "virtual time did not advance 10 ms after the self test");
  }

  // expose: one exposure of the code.
  const std::string expose = ask("expose " + options.code + " " + std::to_string(options.slot_us));
  check.expect(expose.rfind("done", 0) == 0 &&
                   field(expose, "slots") == static_cast<long long>(code.size()) &&
                   field(expose, "slot_us") == options.slot_us &&
                   field(expose, "writes") == static_cast<long long>(code.size()) + 1,
               "expose reply '" + expose + "'");

  const std::string unknown = ask("fly-to-the-moon");
  check.expect(unknown.rfind("error:", 0) == 0, "unknown command reply '" + unknown + "'");

  const std::string status = ask("status");
  check.expect(status.rfind("status state idle", 0) == 0, "status reply '" + status + "'");

  process.stop();  // flushes QEMU's log
  const std::vector<std::uint32_t> writes = bsrr_writes(read_file(log_path));
  const auto total = field(status, "led_writes");
  check.expect(total && *total == static_cast<long long>(writes.size()),
               "the unimp log holds " + std::to_string(writes.size()) +
                   " GPIOA BSRR writes, the firmware counted " +
                   (total ? std::to_string(*total) : std::string("?")));

  std::vector<unsigned> steps;
  for (int led = 0; led < kBoard.pins.led_count; ++led) steps.push_back(1u << led);
  if (auto first = field(selftest, "first_write"))
    check_sequence(check, "selftest", writes, *first, steps, kBoard.pins);
  if (auto first = field(expose, "first_write"))
    check_sequence(check, "expose", writes, *first, code, kBoard.pins);

  if (check.failures() != 0) {
    std::cout << check.failures() << " check(s) failed; log: " << log_path << "\n";
    return 1;
  }
  std::cout << "PASS: version, selftest (" << steps.size() << " LEDs) and a " << code.size()
            << "-slot exposure match the " << writes.size() << " GPIOA BSRR writes in " << log_path
            << "\n";
  return 0;
}
