// The fw-qemu console (port/qemu/src/console.cpp) on the simulation port: the
// same lines the QEMU test sends, with the LED bank checked on the virtual clock.

#include <gtest/gtest.h>

#include <cstdint>
#include <span>
#include <string>
#include <string_view>

#include "flutterscan/common/led_code.hpp"
#include "flutterscan/common/sequencer.hpp"
#include "flutterscan/firmware/command_handler.hpp"
#include "flutterscan/firmware/controller.hpp"
#include "flutterscan/firmware/qemu/console.hpp"
#include "flutterscan/firmware/qemu/qemu_board.hpp"
#include "flutterscan/firmware/sim/sim_port.hpp"

namespace flutterscan::firmware::qemu {
namespace {

constexpr std::string_view kMaxMin = "2212441414112412441224111241244244242212442211444144";

/// The console's device on SimPort: the strobe goes straight to the controller.
class SimConsoleDevice final : public ConsoleDevice {
 public:
  SimConsoleDevice(sim::SimPort& port, Controller& controller)
      : port_(port), controller_(controller) {}
  void write(std::string_view text) override { output.append(text); }
  void set_strobe(bool high) override { controller_.on_strobe_edge(high, port_.now_us()); }
  void add_encoder_counts(std::int32_t counts) override { port_.add_encoder_counts(counts); }
  std::uint32_t led_write_count() override {
    return static_cast<std::uint32_t>(port_.led_transitions().size());
  }
  std::uint64_t now_us() override { return port_.now_us(); }
  void wait() override { port_.run_for(10); }
  std::size_t handle(CommandHandler& handler, std::span<const std::uint8_t> request,
                     std::span<std::uint8_t> reply) override {
    return handler.handle(request, reply);
  }

  std::string output;

 private:
  sim::SimPort& port_;
  Controller& controller_;
};

class QemuConsoleTest : public ::testing::Test {
 protected:
  QemuConsoleTest()
      : board_(qemu_board_config()),
        port_(board_.pins),
        controller_(port_, board_),
        handler_(controller_),
        device_(port_, controller_),
        console_(handler_, device_) {
    controller_.start();
    // The guard counts the LEDs hot at every boot (their supply is not the
    // MCU's): the console's commands come a second later, as a user's would.
    port_.run_until(1'000'000);
  }

  /// Feeds `line` and a newline; returns what the console wrote.
  std::string run(std::string_view line) {
    device_.output.clear();
    for (const char c : line) console_.feed(c);
    console_.feed('\n');
    return device_.output;
  }

  BoardConfig board_;
  sim::SimPort port_;
  Controller controller_;
  CommandHandler handler_;
  SimConsoleDevice device_;
  Console console_;
};

TEST_F(QemuConsoleTest, VersionReportsFirmwareAndProtocol) {
  const std::string want =
      "version firmware " + std::to_string(board_.firmware_major) + "." +
      std::to_string(board_.firmware_minor) + "." + std::to_string(board_.firmware_patch) +
      " protocol " + std::to_string(protocol::kProtocolMajor) + "." +
      std::to_string(protocol::kProtocolMinor) + " board 2 leds 3 build " + "0x00000000\n";
  EXPECT_EQ(run("version"), want);
}

TEST_F(QemuConsoleTest, SelfTestStepsEachLed) {
  port_.clear_led_transitions();
  EXPECT_EQ(run("selftest 500"), "selftest ok leds 3 step_us 500 first_write 0 writes 4\n");
  const auto& t = port_.led_transitions();
  ASSERT_EQ(t.size(), 4u);
  for (int led = 0; led < 3; ++led) {
    EXPECT_EQ(t[static_cast<std::size_t>(led)].led_mask, 1u << led);
    EXPECT_EQ(t[static_cast<std::size_t>(led)].time_us - t[0].time_us,
              500u * static_cast<unsigned>(led));
  }
  EXPECT_EQ(t[3].led_mask, 0u);
}

TEST_F(QemuConsoleTest, ExposePlaysTheCodeOnceThroughTheCommandHandler) {
  port_.clear_led_transitions();
  const std::string reply = run("expose " + std::string(kMaxMin) + " 100");
  EXPECT_EQ(reply, "done frame 1 slots 52 slot_us 100 first_write 0 writes 53\n");
  const auto code = LedCode::parse(kMaxMin, 3, CodeRule::kOneOfN);
  ASSERT_TRUE(code.ok());
  const auto& t = port_.led_transitions();
  ASSERT_GE(t.size(), 53u);
  for (int slot = 0; slot < 52; ++slot) {
    const auto& w = t[static_cast<std::size_t>(slot)];
    EXPECT_EQ(w.bsrr, bsrr_for_mask(code.value().mask(slot), board_.pins)) << "slot " << slot;
    EXPECT_EQ(w.led_mask, code.value().mask(slot)) << "slot " << slot;
    EXPECT_EQ(w.time_us - t[0].time_us, 100u * static_cast<unsigned>(slot)) << "slot " << slot;
  }
  EXPECT_EQ(t[52].led_mask, 0u);
  // Only the disarm's all-off write follows.
  for (std::size_t i = 53; i < t.size(); ++i) EXPECT_EQ(t[i].led_mask, 0u);
  EXPECT_EQ(controller_.state(), protocol::ControllerState::kIdle);
  EXPECT_EQ(run("status").rfind("status state idle mode slave code 0 slot_us 100 frames 1", 0), 0u);
}

TEST_F(QemuConsoleTest, LongCodesGoInSeveralChunks) {
  std::string digits;
  for (int i = 0; i < 130; ++i) digits += "124"[i % 3];
  port_.clear_led_transitions();
  EXPECT_EQ(run("expose " + digits + " 10"),
            "done frame 1 slots 130 slot_us 10 first_write 0 writes 131\n");
}

TEST_F(QemuConsoleTest, BadInputGetsAnErrorLine) {
  EXPECT_EQ(run("launch"), "error: unknown command 'launch' (try help)\n");
  // Digit 3 lights two LEDs: the controller refuses it (SetCode with the one-of-N flag).
  EXPECT_EQ(run("expose 1234 100"), "error: SetCode: invalid code\n");
  // Digit 8 is LED 3, which a 3-LED board lacks: the console's parse says where.
  const std::string no_such_led = run("expose 1284 100");
  EXPECT_EQ(no_such_led.rfind("error: ", 0), 0u) << no_such_led;
  EXPECT_NE(no_such_led.find("slot 2"), std::string::npos) << no_such_led;
  EXPECT_EQ(run("expose 124").rfind("error: usage", 0), 0u);
  EXPECT_EQ(run("expose 124 0"), "error: SetTiming: argument out of range\n");
  EXPECT_EQ(run("selftest x").rfind("error: usage", 0), 0u);
  EXPECT_EQ(run("encoder -5"), "encoder -5\n");
  EXPECT_EQ(port_.encoder_count(), -5);
  EXPECT_EQ(run(""), "");
}

}  // namespace
}  // namespace flutterscan::firmware::qemu
