// The product image's strobe path on the emulated chip (emu_chip.hpp; label
// emu, issue 15 item 4): reset -> bootloader -> application start-up -> its
// main loop, with a USB host on the OTG_FS core (emu_usb_host.hpp), then
// strobe edges on the TIM2 capture input. Every instruction is the real
// fw-stm32f405 images': the host's requests go in as HID reports on EP1 OUT
// through the image's OTG_FS driver, device core and command handler, the
// replies and exposure events come back on EP1 IN; the main loop sleeps in
// `wfi` between SysTick (1 kHz) and OTG_FS wake-ups, pre-arms the next table
// when the guard accepts it, and the TIM2 and DMA2 stream 5 interrupts are
// taken as the NVIC would. What is asserted is what GPIOC's output register
// did, cycle by cycle: DMA2 stream 5 plays the selected code's BSRR words in
// order on TIM1 updates and ends all-off, and an edge the guard must refuse
// lights nothing.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "emu_chip.hpp"
#include "emu_product.hpp"
#include "emu_usb_host.hpp"
#include "flutterscan/common/protocol.hpp"
#include "flutterscan/firmware/settings.hpp"

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
    if (const std::string missing = load_product(chip_); !missing.empty()) GTEST_SKIP() << missing;
    ASSERT_EQ(chip_.run(), "application");
    // Start-up (clocks, port, controller, watchdog, SysTick, OTG_FS with its
    // 25 ms wait for device mode), then the host enumerates it.
    ASSERT_EQ(host_.enumerate(5), "");
    ASSERT_EQ(chip_.otg_fs().address(), 5);
  }

  /// One HID request report over USB; its reply's status.
  proto::Status send(const std::array<std::uint8_t, proto::kReportSize>& report) {
    const std::string error = host_.request(report, &reply_);
    EXPECT_EQ(error, "");
    if (!error.empty()) return static_cast<proto::Status>(0xFF);
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
  /// `us` microseconds of the running product and the bus.
  void run_us(std::uint64_t us) { ASSERT_EQ(host_.run_for(us * kUs), ""); }
  /// A strobe pulse: active edge now, inactive 20 us later, then idle.
  void strobe_pulse(std::uint64_t idle_after_us) {
    chip_.strobe_pin(true);
    run_us(20);
    chip_.strobe_pin(false);
    run_us(idle_after_us);
  }
  std::uint32_t guard_hits() {
    EXPECT_EQ(send(proto::Command::kGetStatus), proto::Status::kOk);
    std::uint32_t hits = 0;
    std::memcpy(&hits,
                reply_.data() + proto::kHeaderSize + offsetof(proto::StatusReply, guard_hits),
                sizeof hits);
    return hits;
  }
  /// Exposure event `i` the host read from EP1 IN.
  proto::ExposureEvent exposure_event(std::size_t i) const {
    proto::ExposureEvent e{};
    std::memcpy(&e, host_.events().at(i).data() + proto::kHeaderSize, sizeof e);
    return e;
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
  UsbHost host_{chip_};
  std::uint8_t sequence_ = 0;
  std::array<std::uint8_t, proto::kReportSize> reply_{};
};

TEST_F(StrobeEmu, AnEdgePlaysTheSelectedCodeThroughDmaAndEndsAllOff) {
  configure_and_arm();
  // Armed in slave mode, the guard accepting: the table waits in hardware.
  ASSERT_TRUE(slot_table_prearmed());
  run_us(100);
  const std::size_t before = chip_.gpioc_writes().size();
  const std::uint64_t edge = chip_.cycles();
  strobe_pulse(1000);
  expect_one_exposure(writes_since(before), edge);
  EXPECT_EQ(guard_hits(), 0u);
  // Its exposure event came in on EP1 IN: frame 1, code 0, no flag but the first code's.
  ASSERT_EQ(host_.events().size(), 1u);
  const proto::ExposureEvent event = exposure_event(0);
  EXPECT_EQ(event.frame_counter, 1u);
  EXPECT_EQ(event.code_id, 0u);
  EXPECT_EQ(event.flags & proto::kEventGuardHit, 0u);
}

// After an exposure, the duty cap holds the next one off for kMinPeriodUs: the
// main loop does not pre-arm, an edge inside that time is refused in the TIM2
// interrupt before any LED lights (its event says so), and one after it plays.
TEST_F(StrobeEmu, TheGuardRefusesAnEdgeTooSoonBeforeAnyLedLights) {
  configure_and_arm();
  run_us(100);
  const std::uint64_t first = chip_.cycles();
  strobe_pulse(800);
  EXPECT_FALSE(slot_table_prearmed());  // at +~820 us the guard refuses: nothing waits in hardware
  run_us(200);
  const std::size_t before = chip_.gpioc_writes().size();
  strobe_pulse(600);  // an edge at +~1020 us: half the minimum period
  for (const Chip::PinWrite& w : writes_since(before)) {
    EXPECT_EQ(w.bsrr & 0xFFFFu, 0u) << "an LED was set at cycle " << w.cycle;
    EXPECT_EQ(w.odr & 0x7u, 0u);
  }
  EXPECT_EQ(chip_.io(kGpioCBase + kGpioOdr) & 0x7u, 0u);
  EXPECT_FALSE(slot_table_prearmed());
  // Past the minimum period, and the minimum off-time after the first
  // exposure's last lit slot (its runs would join), the main loop (woken at
  // 1 kHz) pre-arms again and an edge plays.
  const std::uint64_t now_us = (chip_.cycles() - first) / kUs;
  ASSERT_LT(now_us, kMinPeriodUs);
  const std::uint64_t cooled_us =
      std::max<std::uint64_t>(kMinPeriodUs, kMasks.size() * kSlotUs + kLedMinOffTimeUs);
  run_us(cooled_us - now_us + 1100);
  ASSERT_TRUE(slot_table_prearmed());
  const std::size_t third = chip_.gpioc_writes().size();
  const std::uint64_t edge = chip_.cycles();
  strobe_pulse(1000);
  expect_one_exposure(writes_since(third), edge);
  EXPECT_EQ(guard_hits(), 1u);
  ASSERT_EQ(host_.events().size(), 3u);
  EXPECT_EQ(exposure_event(0).flags & proto::kEventGuardHit, 0u);
  EXPECT_NE(exposure_event(1).flags & proto::kEventGuardHit, 0u);
  EXPECT_EQ(exposure_event(2).flags & proto::kEventGuardHit, 0u);
}

// The on-time cap: a code that keeps an LED on longer than its max_on_time is
// refused by Arm (an edge then lights nothing and reports nothing) and, once
// armed with a code within the cap, by SelectCode: the next edge plays the
// code within the cap.
TEST_F(StrobeEmu, TheOnTimeCapRefusesACodeBeforeAnyLedLights) {
  ASSERT_EQ(upload(1, {0b001, 0b001, 0b001, 0b001, 0b001, 0b010}),
            proto::Status::kOk);  // PC0 on 500 us
  ASSERT_EQ(send(proto::Command::kSetTiming,
                 proto::SetTimingRequest{
                     kSlotUs, 0, static_cast<std::uint8_t>(proto::SlotTimeSource::kFixed), {}}),
            proto::Status::kOk);
  ASSERT_EQ(send(proto::Command::kSetMode,
                 proto::SetModeRequest{static_cast<std::uint8_t>(proto::SyncMode::kSlave), 0, {}}),
            proto::Status::kOk);
  proto::SetGuardRequest guard{};
  guard.max_on_time_us.fill(450);
  guard.max_duty_permille.fill(kProductLedCeiling.max_duty_permille[0]);
  ASSERT_EQ(send(proto::Command::kSetGuard, guard), proto::Status::kOk);
  ASSERT_EQ(upload(0, std::vector<std::uint8_t>(kMasks.begin(), kMasks.end())),
            proto::Status::kOk);  // no joined run longer than four slots (PC0: slots 0 and 3)
  ASSERT_EQ(send(proto::Command::kSelectCode, proto::SelectCodeRequest{1, {}}), proto::Status::kOk);
  EXPECT_EQ(send(proto::Command::kArm), proto::Status::kGuardLimit);
  EXPECT_FALSE(slot_table_prearmed());
  std::size_t before = chip_.gpioc_writes().size();
  strobe_pulse(1000);
  for (const Chip::PinWrite& w : writes_since(before))
    EXPECT_EQ(w.bsrr & 0xFFFFu, 0u) << "an LED was set at cycle " << w.cycle;
  EXPECT_EQ(chip_.io(kGpioCBase + kGpioOdr) & 0x7u, 0u);
  EXPECT_TRUE(host_.events().empty());
  // Armed with code 0; selecting code 1 is refused and the next edge plays code 0.
  ASSERT_EQ(send(proto::Command::kSelectCode, proto::SelectCodeRequest{0, {}}), proto::Status::kOk);
  ASSERT_EQ(send(proto::Command::kArm), proto::Status::kOk);
  EXPECT_EQ(send(proto::Command::kSelectCode, proto::SelectCodeRequest{1, {}}),
            proto::Status::kGuardLimit);
  run_us(1100);
  ASSERT_TRUE(slot_table_prearmed());
  before = chip_.gpioc_writes().size();
  const std::uint64_t edge = chip_.cycles();
  strobe_pulse(1000);
  expect_one_exposure(writes_since(before), edge);
  ASSERT_EQ(host_.events().size(), 1u);
  EXPECT_EQ(exposure_event(0).code_id, 0u);
}

// Issue 15 finding 4 on the product image: SelectCode of a second and then a
// third code while DMA2 stream 5 plays the first one (48 slots, 4.8 ms: long
// enough for two requests over USB) builds them into tables the DMA is not
// reading: the exposure plays the first code's words to its all-off end,
// untouched; the code selected last plays on the next edge.
TEST_F(StrobeEmu, SelectingOtherCodesWhileTheDmaPlaysLeavesItsTableAlone) {
  std::vector<std::uint8_t> playing;
  for (int i = 0; i < 48; ++i) playing.push_back(static_cast<std::uint8_t>(1u << (i % 3)));
  std::vector<std::uint8_t> longer(12, 0b111);
  ASSERT_EQ(upload(1, longer), proto::Status::kOk);
  longer.assign(16, 0b101);
  ASSERT_EQ(upload(2, longer), proto::Status::kOk);
  ASSERT_EQ(upload(3, playing), proto::Status::kOk);
  configure_and_arm(5000, kProductLedCeiling.max_duty_permille[0]);  // SelectCode accepts them all
  ASSERT_EQ(send(proto::Command::kSelectCode, proto::SelectCodeRequest{3, {}}), proto::Status::kOk);
  run_us(1100);
  ASSERT_TRUE(slot_table_prearmed());
  const std::size_t before = chip_.gpioc_writes().size();
  const std::uint64_t edge = chip_.cycles();
  chip_.strobe_pin(true);
  run_us(150);  // the TIM2 interrupt ran; slot 1 playing
  ASSERT_EQ(send(proto::Command::kSelectCode, proto::SelectCodeRequest{1, {}}), proto::Status::kOk);
  ASSERT_EQ(send(proto::Command::kSelectCode, proto::SelectCodeRequest{2, {}}), proto::Status::kOk);
  ASSERT_LT(chip_.cycles() - edge, playing.size() * kSlotUs * kUs);  // still inside the exposure
  chip_.strobe_pin(false);
  run_us(5000);
  expect_one_exposure(writes_since(before), edge, playing);
  run_us(5000);
  ASSERT_TRUE(slot_table_prearmed());
  const std::size_t next = chip_.gpioc_writes().size();
  const std::uint64_t next_edge = chip_.cycles();
  strobe_pulse(2000);
  expect_one_exposure(writes_since(next), next_edge, longer);
}

}  // namespace
}  // namespace flutterscan::firmware::emu
