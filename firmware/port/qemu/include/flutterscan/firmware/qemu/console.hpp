#pragma once
// The fw-qemu image's line console (USART1 in QEMU). Every command goes to the
// controller as the HID request reports the USB interface would carry
// (common/protocol.hpp encoders -> CommandHandler), so the console exercises
// the same path as the host tool. One reply line per command, no echo:
//
//   version                 -> "version firmware 0.1.0 protocol 1.0 board 2 leds 3 build
//   0x00000000" status                  -> "status state idle mode slave code 0 frames 1 ...
//   led_writes 58" selftest [STEP_US]      -> "selftest ok leds 3 step_us 1000 first_write 1 writes
//   4" expose CODE SLOT_US     -> "done frame 1 slots 52 slot_us 100 first_write 5 writes 53"
//   encoder COUNTS          -> "encoder 12"
//   help                    -> the command list
//   anything else           -> "error: ..."
//
// `expose` uploads CODE (digit notation, one-of-3) as code 0 with SetCode,
// SelectCode, SetTiming (fixed slot time), SetMode (slave: the console plays the
// camera strobe), Arm; raises the strobe, waits for the exposure event, drops the
// strobe and disarms. first_write/writes say which LED bank writes (counted from
// 0 at boot, as they appear in QEMU's `-d unimp` log) belong to the sequence.
// Hardware-independent (host-compilable): the device is behind ConsoleDevice.

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>

#include "flutterscan/common/protocol.hpp"
#include "flutterscan/firmware/command_handler.hpp"

namespace flutterscan::firmware::qemu {

/// \brief What the console needs from the board.
class ConsoleDevice {
 public:
  /// \brief Sends `text` to the console.
  virtual void write(std::string_view text) = 0;
  /// \brief Sets the strobe input's level.
  virtual void set_strobe(bool high) = 0;
  /// \brief Adds encoder counts.
  virtual void add_encoder_counts(std::int32_t counts) = 0;
  /// \brief LED bank writes since boot.
  virtual std::uint32_t led_write_count() = 0;
  /// \brief Monotonic microseconds.
  virtual std::uint64_t now_us() = 0;
  /// \brief Lets time pass while waiting for the sequencer (interrupts run).
  virtual void wait() = 0;
  /// \brief Runs one request through the command handler with the slot and
  /// strobe interrupts masked; returns the reply size.
  virtual std::size_t handle(CommandHandler& handler, std::span<const std::uint8_t> request,
                             std::span<std::uint8_t> reply) = 0;

 protected:
  ~ConsoleDevice() = default;
};

/// \brief Line console over a ConsoleDevice, driving a CommandHandler.
class Console {
 public:
  /// Longest line: "expose " + a 256-slot code + a slot time.
  static constexpr std::size_t kMaxLine = 300;

  /// \brief A console for `handler` on `device` (both must outlive it).
  Console(CommandHandler& handler, ConsoleDevice& device) : handler_(handler), device_(device) {}

  /// \brief Feeds one received character; runs the line at '\n' or '\r'.
  void feed(char c);
  /// \brief Runs one command line (without its newline).
  void execute(std::string_view line);

 private:
  using Report = std::array<std::uint8_t, protocol::kReportSize>;

  /// Sends `request` and returns the reply's status (kBadLength if none came back).
  protocol::Status transact(std::span<const std::uint8_t> request, Report& reply);
  template <typename T>
  protocol::Status request(protocol::Command command, const T& payload, Report& reply);
  protocol::Status request(protocol::Command command, Report& reply);
  std::uint8_t next_sequence() { return sequence_++; }

  void cmd_help();
  void cmd_version();
  void cmd_status();
  void cmd_selftest(std::string_view args);
  void cmd_expose(std::string_view args);
  void cmd_encoder(std::string_view args);
  /// "error: <what>: <status text>".
  void fail(std::string_view what, protocol::Status status);
  void fail(std::string_view what);

  CommandHandler& handler_;
  ConsoleDevice& device_;
  std::array<char, kMaxLine> line_{};
  std::size_t line_length_ = 0;
  bool line_overflow_ = false;
  std::uint8_t sequence_ = 0;
};

}  // namespace flutterscan::firmware::qemu
