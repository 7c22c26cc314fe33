// The product image's strobe path on the emulated chip (emu_chip.hpp; label
// emu, issue 15 item 4): reset -> bootloader -> application start-up, then the
// host's requests, then strobe edges on the TIM2 capture input. Every
// instruction is the real fw-stm32f405 application's.
//
// How the host is played: OTG_FS is not modelled, so the emulation stops
// where the application would initialise USB (OtgFsDevice::init) and from
// there on calls the firmware's own entry points the main loop calls (with
// PRIMASK set, as its InterruptLock does): CommandHandler::handle with the
// 64-byte HID request reports a host sends (built with common/protocol.hpp),
// and Controller::poll (the main loop's pass: it pre-arms the next table once
// the guard accepts it). Between calls the core is idle (`wfi`): TIM2 and DMA2
// stream 5 interrupts are taken as the NVIC would, through the vector table.
// What is asserted is what GPIOC's output register did, cycle by cycle:
// DMA2 stream 5 plays the selected code's BSRR words in order on TIM1 updates
// and ends all-off, and an edge the guard must refuse lights nothing.

#include <gtest/gtest.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "emu_chip.hpp"
#include "emu_elf.hpp"
#include "flutterscan/common/protocol.hpp"
#include "flutterscan/firmware/boot_decision.hpp"

namespace flutterscan::firmware::emu {
namespace {

namespace proto = flutterscan::protocol;

constexpr std::uint64_t kUs = Chip::kCyclesPerUs;
constexpr std::uint32_t kSlotUs = 100;
/// The code: three LEDs (PC0..PC2), four slots.
constexpr std::array<std::uint8_t, 4> kMasks{0b001, 0b010, 0b100, 0b111};
/// The guard: each LED is on 200 us per exposure (two slots); at a 10 % duty
/// cap a new exposure may start 2000 us after the last one started.
constexpr std::uint16_t kDutyPermille = 100;
constexpr std::uint64_t kMinPeriodUs = 2000;

class StrobeEmu : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto boot = Elf::load(FLUTTERSCAN_BOOTLOADER_ELF);
    const auto app = Elf::load(FLUTTERSCAN_FW_STM32F405_ELF);
    const auto image = read_file(FLUTTERSCAN_FW_STM32F405_BIN);
    if (!boot || !app || image.empty())
      GTEST_SKIP() << "no bootloader / application ELF or image (make fw-stm32f405 builds them)";
    const std::uint32_t usb_init =
        app->symbol("_ZN11flutterscan8firmware7stm32f411OtgFsDevice4initEm");
    handle_ = app->symbol(
        "_ZN11flutterscan8firmware14CommandHandler6handleESt4spanIKhLj4294967295EES2_IhLj"
        "4294967295EE");
    poll_ = app->symbol("_ZN11flutterscan8firmware10Controller4pollEb");
    handler_ = app->symbol("_ZN11flutterscan8firmware7stm32f412_GLOBAL__N_117g_handler_storageE");
    controller_ =
        app->symbol("_ZN11flutterscan8firmware7stm32f412_GLOBAL__N_120g_controller_storageE");
    ASSERT_NE(usb_init, 0u);
    ASSERT_NE(handle_, 0u);
    ASSERT_NE(poll_, 0u);
    ASSERT_NE(handler_, 0u);
    ASSERT_NE(controller_, 0u);
    for (const auto& s : boot->segments) chip_.write(s.address, s.bytes);
    chip_.write(kAppBase, image);
    chip_.stop_at(get<std::uint32_t>(image, kAppVectorTableOffset + 4), "application");
    chip_.stop_at(usb_init, "usb init");
    ASSERT_EQ(chip_.run(), "application");
    ASSERT_EQ(chip_.resume(), "usb init");
    // Host buffers and the calls' stack below application_main's frame.
    const std::uint32_t sp = chip_.reg(UC_ARM_REG_SP) & ~7u;
    request_at_ = sp - 256;
    reply_at_ = sp - 128;
    stack_top_ = sp - 512;
  }

  /// One HID request report through CommandHandler::handle; its reply's status.
  proto::Status send(const std::array<std::uint8_t, proto::kReportSize>& report) {
    chip_.write(request_at_, std::vector<std::uint8_t>(report.begin(), report.end()));
    std::uint32_t size = 0;
    const std::string out = chip_.call(
        handle_, {handler_, request_at_, proto::kReportSize, reply_at_, proto::kReportSize},
        stack_top_, &size);
    EXPECT_EQ(out, "returned");
    EXPECT_EQ(size, proto::kReportSize);
    reply_.fill(0);
    for (std::size_t i = 0; i < reply_.size(); i += 4) {
      const std::uint32_t w = chip_.read_word(reply_at_ + static_cast<std::uint32_t>(i));
      for (std::size_t k = 0; k < 4; ++k) reply_[i + k] = static_cast<std::uint8_t>(w >> (8 * k));
    }
    EXPECT_EQ(reply_[0], report[0]);  // command echoed
    EXPECT_EQ(reply_[1], report[1]);  // sequence echoed
    return static_cast<proto::Status>(reply_[3]);
  }
  template <typename T>
  proto::Status send(proto::Command command, const T& payload) {
    std::array<std::uint8_t, proto::kReportSize> r{};
    proto::encode_request(command, ++sequence_, payload, r);
    return send(r);
  }
  proto::Status send(proto::Command command) {
    std::array<std::uint8_t, proto::kReportSize> r{};
    proto::encode_request(command, ++sequence_, r);
    return send(r);
  }
  /// One pass of the main loop's controller work (Controller::poll).
  void main_loop_pass() { EXPECT_EQ(chip_.call(poll_, {controller_, 1}, stack_top_), "returned"); }
  /// A strobe pulse: active edge now, inactive 20 us later, then idle.
  void strobe_pulse(std::uint64_t idle_after_us) {
    chip_.strobe_pin(true);
    ASSERT_EQ(chip_.idle_for(20 * kUs), "idle");
    chip_.strobe_pin(false);
    ASSERT_EQ(chip_.idle_for(idle_after_us * kUs), "idle");
  }
  std::uint32_t guard_hits() {
    EXPECT_EQ(send(proto::Command::kGetStatus), proto::Status::kOk);
    std::uint32_t hits = 0;
    std::memcpy(&hits,
                reply_.data() + proto::kHeaderSize + offsetof(proto::StatusReply, guard_hits),
                sizeof hits);
    return hits;
  }
  /// The writes to GPIOC BSRR from index `from` on.
  std::vector<Chip::PinWrite> writes_since(std::size_t from) const {
    const auto& all = chip_.gpioc_writes();
    return {all.begin() + static_cast<std::ptrdiff_t>(from), all.end()};
  }
  bool slot_table_prearmed() const {
    return chip_.io(kTim1Base + kTimSmcr) == 0x16u;  // TS = ITR1 (TIM2), SMS = trigger
  }

  /// Uploads `masks` as code `id` (one chunk: at most 52 slots).
  proto::Status upload(std::uint8_t id, const std::vector<std::uint8_t>& masks) {
    proto::SetCodeRequest code{};
    code.code_id = id;
    code.led_count = 3;
    code.total_slots = static_cast<std::uint16_t>(masks.size());
    code.first_slot = 0;
    code.slot_count = static_cast<std::uint8_t>(masks.size());
    for (std::size_t i = 0; i < masks.size(); ++i) code.masks[i] = masks[i];
    return send(proto::Command::kSetCode, code);
  }

  void configure_and_arm(std::uint32_t max_on_us = 1000, std::uint16_t duty = kDutyPermille) {
    ASSERT_EQ(send(proto::Command::kSetTiming,
                   proto::SetTimingRequest{
                       kSlotUs, 0, static_cast<std::uint8_t>(proto::SlotTimeSource::kFixed), {}}),
              proto::Status::kOk);
    ASSERT_EQ(
        send(proto::Command::kSetMode,
             proto::SetModeRequest{static_cast<std::uint8_t>(proto::SyncMode::kSlave), 0, {}}),
        proto::Status::kOk);
    proto::SetGuardRequest guard{};
    guard.max_on_time_us.fill(max_on_us);
    guard.max_duty_permille.fill(duty);
    ASSERT_EQ(send(proto::Command::kSetGuard, guard), proto::Status::kOk);
    ASSERT_EQ(upload(0, std::vector<std::uint8_t>(kMasks.begin(), kMasks.end())),
              proto::Status::kOk);
    ASSERT_EQ(send(proto::Command::kSelectCode, proto::SelectCodeRequest{0, {}}),
              proto::Status::kOk);
    ASSERT_EQ(send(proto::Command::kArm), proto::Status::kOk);
  }

  /// Checks that `writes` are one exposure of kMasks started by the edge at
  /// `edge`: DMA writes only, the code's BSRR words in order one slot apart,
  /// the first one TIM1 tick after the edge, then all-off.
  void expect_one_exposure(const std::vector<Chip::PinWrite>& writes, std::uint64_t edge) {
    expect_one_exposure(writes, edge, std::vector<std::uint8_t>(kMasks.begin(), kMasks.end()));
  }
  void expect_one_exposure(const std::vector<Chip::PinWrite>& writes, std::uint64_t edge,
                           const std::vector<std::uint8_t>& masks) {
    ASSERT_EQ(writes.size(), masks.size() + 1);
    const std::uint32_t psc = chip_.io(kTim1Base + 0x28);
    const std::uint32_t arr = chip_.io(kTim1Base + 0x2C);
    EXPECT_EQ((psc + 1ull) * (arr + 1ull), kSlotUs * kUs);  // TIM1 period = one slot
    for (std::size_t i = 0; i < writes.size(); ++i) {
      const std::uint32_t mask = i < masks.size() ? masks[i] : 0u;
      const std::uint32_t word = mask | ((~mask & 0x7u) << 16);
      EXPECT_TRUE(writes[i].by_dma) << i;
      EXPECT_EQ(writes[i].bsrr, word) << i;
      EXPECT_EQ(writes[i].odr & 0x7u, mask) << i;
      EXPECT_EQ(writes[i].cycle, edge + (psc + 1ull) + i * kSlotUs * kUs) << i;
    }
    EXPECT_EQ(chip_.io(kGpioCBase + kGpioOdr) & 0x7u, 0u);
    EXPECT_EQ(chip_.io(kTim1Base + kTimCr1) & 1u, 0u);  // the TC interrupt stopped TIM1
  }

  Chip chip_;
  std::uint32_t handle_ = 0, poll_ = 0, handler_ = 0, controller_ = 0;
  std::uint32_t request_at_ = 0, reply_at_ = 0, stack_top_ = 0;
  std::uint8_t sequence_ = 0;
  std::array<std::uint8_t, proto::kReportSize> reply_{};
};

TEST_F(StrobeEmu, AnEdgePlaysTheSelectedCodeThroughDmaAndEndsAllOff) {
  configure_and_arm();
  // Armed in slave mode, the guard accepting: the table waits in hardware.
  ASSERT_TRUE(slot_table_prearmed());
  ASSERT_EQ(chip_.idle_for(100 * kUs), "idle");
  const std::size_t before = chip_.gpioc_writes().size();
  const std::uint64_t edge = chip_.cycles();
  strobe_pulse(1000);
  expect_one_exposure(writes_since(before), edge);
  EXPECT_EQ(guard_hits(), 0u);
}

// After an exposure, the duty cap holds the next one off for kMinPeriodUs: the
// main loop does not pre-arm, an edge inside that time is refused in the TIM2
// interrupt before any LED lights, and one after it plays again.
TEST_F(StrobeEmu, TheGuardRefusesAnEdgeTooSoonBeforeAnyLedLights) {
  configure_and_arm();
  ASSERT_EQ(chip_.idle_for(100 * kUs), "idle");
  const std::uint64_t first = chip_.cycles();
  strobe_pulse(800);
  main_loop_pass();
  EXPECT_FALSE(slot_table_prearmed());  // at +~820 us the guard refuses: nothing waits in hardware
  ASSERT_EQ(chip_.idle_for(200 * kUs), "idle");
  const std::size_t before = chip_.gpioc_writes().size();
  strobe_pulse(600);  // an edge at +~1000 us: half the minimum period
  main_loop_pass();
  for (const Chip::PinWrite& w : writes_since(before)) {
    EXPECT_EQ(w.bsrr & 0xFFFFu, 0u) << "an LED was set at cycle " << w.cycle;
    EXPECT_EQ(w.odr & 0x7u, 0u);
  }
  EXPECT_EQ(chip_.io(kGpioCBase + kGpioOdr) & 0x7u, 0u);
  EXPECT_EQ(guard_hits(), 1u);
  // Past the minimum period: the main loop pre-arms again and an edge plays.
  const std::uint64_t now_us = (chip_.cycles() - first) / kUs;
  ASSERT_LT(now_us, kMinPeriodUs);
  ASSERT_EQ(chip_.idle_for((kMinPeriodUs - now_us + 50) * kUs), "idle");
  main_loop_pass();
  ASSERT_TRUE(slot_table_prearmed());
  const std::size_t third = chip_.gpioc_writes().size();
  const std::uint64_t edge = chip_.cycles();
  strobe_pulse(1000);
  expect_one_exposure(writes_since(third), edge);
}

// Issue 15 finding 4 on the product image: SelectCode of a second and then a
// third code (longer, all LEDs on at the end) while DMA2 stream 5 plays the
// first one builds them into tables the DMA is not reading: the exposure
// plays the first code's words to its all-off end, untouched.
TEST_F(StrobeEmu, SelectingOtherCodesWhileTheDmaPlaysLeavesItsTableAlone) {
  std::vector<std::uint8_t> longer(12, 0b111);
  ASSERT_EQ(upload(1, longer), proto::Status::kOk);
  longer.assign(16, 0b101);
  ASSERT_EQ(upload(2, longer), proto::Status::kOk);
  configure_and_arm(5000, 1000);  // codes 1 and 2 within the guard: SelectCode accepts them
  main_loop_pass();
  ASSERT_TRUE(slot_table_prearmed());
  const std::size_t before = chip_.gpioc_writes().size();
  const std::uint64_t edge = chip_.cycles();
  chip_.strobe_pin(true);
  ASSERT_EQ(chip_.idle_for(150 * kUs), "idle");  // the TIM2 interrupt ran; slot 1 playing
  ASSERT_EQ(send(proto::Command::kSelectCode, proto::SelectCodeRequest{1, {}}), proto::Status::kOk);
  ASSERT_EQ(chip_.idle_for(50 * kUs), "idle");
  ASSERT_EQ(send(proto::Command::kSelectCode, proto::SelectCodeRequest{2, {}}), proto::Status::kOk);
  main_loop_pass();
  ASSERT_LT(chip_.cycles() - edge, kMasks.size() * kSlotUs * kUs);  // still inside the exposure
  chip_.strobe_pin(false);
  ASSERT_EQ(chip_.idle_for(1000 * kUs), "idle");
  expect_one_exposure(writes_since(before), edge);
  // The code selected last plays on the next edge, pre-armed by the main loop
  // once its 1600 us of LED 0 fit the duty cap (100 %) since this edge.
  main_loop_pass();
  EXPECT_FALSE(slot_table_prearmed());  // 1200 us since this exposure began
  ASSERT_EQ(chip_.idle_for(500 * kUs), "idle");
  main_loop_pass();
  ASSERT_TRUE(slot_table_prearmed());
  const std::size_t next = chip_.gpioc_writes().size();
  const std::uint64_t next_edge = chip_.cycles();
  chip_.strobe_pin(true);
  ASSERT_EQ(chip_.idle_for(20 * kUs), "idle");
  chip_.strobe_pin(false);
  ASSERT_EQ(chip_.idle_for(2000 * kUs), "idle");
  expect_one_exposure(writes_since(next), next_edge, longer);
}

}  // namespace
}  // namespace flutterscan::firmware::emu
