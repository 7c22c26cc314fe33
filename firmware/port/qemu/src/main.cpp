// The fw-qemu image: the firmware core on QEMU's netduinoplus2 with a line
// console on USART1 instead of USB (QEMU models no USB device controller).
// The application lives here rather than in firmware/app/, which is the USB
// application of the product image; see firmware/README.md.

#include <string_view>

#include "flutterscan/firmware/command_handler.hpp"
#include "flutterscan/firmware/controller.hpp"
#include "flutterscan/firmware/qemu/console.hpp"
#include "flutterscan/firmware/qemu/qemu_board.hpp"
#include "flutterscan/firmware/qemu/qemu_port.hpp"
#include "flutterscan/firmware/qemu/registers.hpp"

namespace flutterscan::firmware::qemu {
namespace {

/// USART1 as the console, polled. QEMU ignores the baud rate; BRR holds
/// 115200 baud at the 84 MHz APB2 clock a 168 MHz F405 runs it at (RM0090 30.3.4:
/// USARTDIV = 84e6 / (16 * 115200) = 45.57 -> mantissa 45, fraction 9).
class Usart1 {
 public:
  static void init() {
    reg::set_bits(reg::rcc::kAhb1Enr, reg::rcc::kAhb1EnrGpioA);
    reg::set_bits(reg::rcc::kApb2Enr, reg::rcc::kApb2EnrUsart1);
    // PA9 = TX, PA10 = RX, alternate function 7.
    reg::modify(reg::gpioa::kModer, (0b11u << 18) | (0b11u << 20),
                (reg::gpioa::kModeAlternate << 18) | (reg::gpioa::kModeAlternate << 20));
    reg::modify(reg::gpioa::kAfrh, (0xFu << 4) | (0xFu << 8),
                (reg::usart1::kPinAf << 4) | (reg::usart1::kPinAf << 8));
    reg::at(reg::usart1::kBrr) = (45u << 4) | 9u;
    reg::at(reg::usart1::kCr1) = reg::usart1::kCr1Ue | reg::usart1::kCr1Te | reg::usart1::kCr1Re;
  }
  static void write(std::string_view text) {
    for (const char c : text) {
      while ((reg::at(reg::usart1::kSr) & reg::usart1::kSrTxe) == 0) {
      }
      reg::at(reg::usart1::kDr) = static_cast<std::uint8_t>(c);
    }
  }
  /// \brief The next received byte, or -1 if none waits.
  static int read() {
    if ((reg::at(reg::usart1::kSr) & reg::usart1::kSrRxne) == 0) return -1;
    return static_cast<int>(reg::at(reg::usart1::kDr) & 0xFFu);
  }
};

/// The console's view of this board.
class QemuConsoleDevice final : public ConsoleDevice {
 public:
  explicit QemuConsoleDevice(QemuPort& port) : port_(port) {}
  void write(std::string_view text) override { Usart1::write(text); }
  void set_strobe(bool high) override { port_.inject_strobe(high); }
  void add_encoder_counts(std::int32_t counts) override { port_.add_encoder_counts(counts); }
  std::uint32_t led_write_count() override { return port_.led_write_count(); }
  std::uint64_t now_us() override { return port_.now_us(); }
  void wait() override { asm volatile("wfi" ::: "memory"); }  // SysTick always wakes us
  std::size_t handle(CommandHandler& handler, std::span<const std::uint8_t> request,
                     std::span<std::uint8_t> reply) override {
    InterruptLock lock;  // controller.hpp: no port callbacks during command handling
    return handler.handle(request, reply);
  }

 private:
  QemuPort& port_;
};

constexpr BoardConfig kBoard = qemu_board_config();

// Trivially destructible, so a global without atexit; constructed by the startup code.
QemuPort g_port(kBoard.pins);

}  // namespace
}  // namespace flutterscan::firmware::qemu

[[noreturn]] void application_main() {
  using namespace flutterscan::firmware;
  using namespace flutterscan::firmware::qemu;
  Usart1::init();
  g_port.init();
  Controller controller(g_port, kBoard);
  controller.start();
  CommandHandler handler(controller);
  QemuConsoleDevice device(g_port);
  Console console(handler, device);
  Usart1::write("flutterscan fw-qemu ready (type help)\n");
  for (;;) {
    controller.poll();
    const int c = Usart1::read();
    if (c >= 0) console.feed(static_cast<char>(c));
  }
}
