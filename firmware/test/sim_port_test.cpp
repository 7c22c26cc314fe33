#include "flutterscan/firmware/sim/sim_port.hpp"

#include <gtest/gtest.h>

#include <array>
#include <limits>
#include <vector>

#include "flutterscan/firmware/sim/sim_flash.hpp"

namespace flutterscan::firmware::sim {
namespace {

const LedPinMap kPins{3, {0, 1, 2, 0}};

/// Records callbacks with their times.
struct RecordingListener final : PortListener {
  std::vector<std::pair<std::uint64_t, bool>> strobes;
  std::vector<std::uint64_t> table_done;
  std::vector<std::uint64_t> frames;
  void on_strobe_edge(bool active, std::uint64_t t) override { strobes.push_back({t, active}); }
  void on_slot_table_done(std::uint64_t t) override { table_done.push_back(t); }
  void on_frame_tick(std::uint64_t t) override { frames.push_back(t); }
};

TEST(SimPort, PlaysATableExactlyOnTheVirtualClock) {
  SimPort port(kPins);
  RecordingListener listener;
  port.set_listener(&listener);
  port.run_until(1000);
  const std::array<std::uint32_t, 3> words = {0x00060001, 0x00050002, 0x00070000};
  ASSERT_EQ(port.start_slot_table(words, 40), PortStatus::kOk);
  port.run_until(1079);
  ASSERT_EQ(port.led_transitions().size(), 2u);
  EXPECT_TRUE(listener.table_done.empty());
  port.run_until(2000);
  const auto& t = port.led_transitions();
  ASSERT_EQ(t.size(), 3u);
  EXPECT_EQ(t[0].time_us, 1000u);
  EXPECT_EQ(t[0].led_mask, 1);
  EXPECT_EQ(t[1].time_us, 1040u);
  EXPECT_EQ(t[1].led_mask, 2);
  EXPECT_EQ(t[2].time_us, 1080u);
  EXPECT_EQ(t[2].led_mask, 0);
  EXPECT_EQ(listener.table_done, std::vector<std::uint64_t>{1080});
  EXPECT_FALSE(port.slot_table_running());
  EXPECT_EQ(port.now_us(), 2000u);
}

TEST(SimPort, NextEventIsTheEarliestScheduled) {
  SimPort port(kPins);
  EXPECT_EQ(port.next_event_us(), std::numeric_limits<std::uint64_t>::max());
  port.inject_strobe(500, 100);
  EXPECT_EQ(port.next_event_us(), 500u);
  const std::array<std::uint32_t, 2> words = {0x00000001, 0x00010000};
  port.run_until(100);
  ASSERT_EQ(port.start_slot_table(words, 300), PortStatus::kOk);
  EXPECT_EQ(port.next_event_us(), 100u);
  port.run_until(100);
  EXPECT_EQ(port.next_event_us(), 400u);
  port.run_until(400);
  EXPECT_EQ(port.next_event_us(), 500u);
  ASSERT_EQ(port.start_frame_timer(1000, 0), PortStatus::kOk);
  EXPECT_EQ(port.next_event_us(), 400u);
  port.run_until(550);
  EXPECT_EQ(port.next_event_us(), 600u);
  port.run_until(600);
  EXPECT_EQ(port.next_event_us(), 1400u);
}

TEST(SimPort, SetBitWinsOverResetBit) {
  SimPort port(kPins);
  port.write_led_bank(0x00010001);
  EXPECT_EQ(port.pin_levels(), 1);
  port.write_led_bank(0x00010000);
  EXPECT_EQ(port.pin_levels(), 0);
}

TEST(SimPort, StrobesArriveInTimeOrder) {
  SimPort port(kPins);
  RecordingListener listener;
  port.set_listener(&listener);
  port.inject_strobe(500, 100);
  port.inject_strobe(200, 50);
  port.run_until(1000);
  const std::vector<std::pair<std::uint64_t, bool>> expected = {
      {200, true}, {250, false}, {500, true}, {600, false}};
  EXPECT_EQ(listener.strobes, expected);
}

TEST(SimPort, EncoderCountsAtTheSetVelocity) {
  SimPort port(kPins);
  port.set_encoder_velocity(10'000);
  port.run_until(5'200);
  EXPECT_EQ(port.encoder_count(), 52);
  port.set_encoder_velocity(-1'000'000);
  port.run_for(10);
  EXPECT_EQ(port.encoder_count(), 42);
  port.add_encoder_counts(8);
  EXPECT_EQ(port.encoder_count(), 50);
}

TEST(SimPort, FrameTimerTicksAndDrivesTheTrigger) {
  SimPort port(kPins);
  RecordingListener listener;
  port.set_listener(&listener);
  port.run_until(100);
  ASSERT_EQ(port.start_frame_timer(1000, 300), PortStatus::kOk);
  EXPECT_EQ(port.next_event_us(), 100u);
  port.run_until(2100);
  EXPECT_EQ(listener.frames, (std::vector<std::uint64_t>{100, 1100, 2100}));
  EXPECT_EQ(port.next_event_us(), 3100u);
  ASSERT_EQ(port.trigger_pulses().size(), 3u);
  EXPECT_EQ(port.trigger_pulses()[1].start_us, 1100u);
  EXPECT_EQ(port.trigger_pulses()[1].width_us, 300u);
  port.stop_frame_timer();
  port.run_until(5000);
  EXPECT_EQ(listener.frames.size(), 3u);
}

TEST(SimPort, FlashProgrammingOnlyClearsBits) {
  SimPort port(kPins, 128);  // two pages of 64 bytes
  ASSERT_EQ(port.config_page_size(), 64u);
  const std::array<std::uint8_t, 2> first = {0xF0, 0x0F};
  const std::array<std::uint8_t, 2> second = {0x3C, 0xFF};
  ASSERT_EQ(port.write_config_page(0, 0, first), PortStatus::kOk);
  ASSERT_EQ(port.write_config_page(0, 0, second), PortStatus::kOk);
  std::array<std::uint8_t, 3> out{};
  ASSERT_EQ(port.read_config_page(0, 0, out), PortStatus::kOk);
  EXPECT_EQ(out, (std::array<std::uint8_t, 3>{0x30, 0x0F, 0xFF}));
  ASSERT_EQ(port.read_config_page(1, 0, out), PortStatus::kOk);
  EXPECT_EQ(out, (std::array<std::uint8_t, 3>{0xFF, 0xFF, 0xFF}));  // the other page
  ASSERT_EQ(port.write_config_page(1, 62, first), PortStatus::kOk);
  EXPECT_EQ(port.flash_page()[126], 0xF0);
  ASSERT_EQ(port.erase_config_page(0), PortStatus::kOk);
  ASSERT_EQ(port.read_config_page(0, 0, out), PortStatus::kOk);
  EXPECT_EQ(out, (std::array<std::uint8_t, 3>{0xFF, 0xFF, 0xFF}));
  EXPECT_EQ(port.flash_page(1)[62], 0xF0);  // erasing page 0 left page 1
  std::array<std::uint8_t, 65> too_much{};
  EXPECT_EQ(port.read_config_page(0, 0, too_much), PortStatus::kError);
  EXPECT_EQ(port.write_config_page(1, 63, first), PortStatus::kError);
}

TEST(SimFlash, ProgrammingOnlyClearsBitsAndResetRestoresTheFreshFlash) {
  SimFlash flash;
  const std::uint32_t base = flash.base();
  const std::array<std::uint8_t, 3> first = {0xF0, 0x0F, 0x00};
  const std::array<std::uint8_t, 3> second = {0x3C, 0xFF, 0xFF};
  ASSERT_EQ(flash.program(base + 16, first), FlashResult::kOk);
  ASSERT_EQ(flash.program(base + 16, second), FlashResult::kOk);
  const auto read = flash.read(base + 15, 5);
  EXPECT_EQ(std::vector<std::uint8_t>(read.begin(), read.end()),
            (std::vector<std::uint8_t>{0xFF, 0x30, 0x0F, 0x00, 0xFF}));
  EXPECT_EQ(flash.program_count(0), 2);
  ASSERT_EQ(flash.erase_sector(1), FlashResult::kOk);
  EXPECT_EQ(flash.erase_count(1), 1);
  flash.set_failures(true, true);

  flash.reset();
  for (const std::uint8_t b : flash.bytes()) ASSERT_EQ(b, 0xFF);
  for (int s = 0; s < static_cast<int>(flash.layout().sectors.size()); ++s) {
    EXPECT_EQ(flash.erase_count(s), 0);
    EXPECT_EQ(flash.program_count(s), 0);
  }
  EXPECT_EQ(flash.program(base, first), FlashResult::kOk);  // failures cleared
  EXPECT_EQ(flash.erase_sector(0), FlashResult::kOk);
}

}  // namespace
}  // namespace flutterscan::firmware::sim

namespace flutterscan::firmware::sim {
namespace {

// The product port's timing (issue 15): a pre-armed table starts on its edge
// in hardware; callbacks come after the interrupt latency, and not before the
// end of the interrupt lock.
TEST(SimPortTiming, APrearmedTableStartsOnTheEdgeBeforeItsLateCallback) {
  SimPort port(kPins);
  RecordingListener listener;
  port.set_listener(&listener);
  port.set_interrupt_latency_us(25);
  const std::array<std::uint32_t, 3> words = {0x00060001, 0x00050002, 0x00070000};
  ASSERT_EQ(port.prearm_slot_table(words, 40), PortStatus::kOk);
  EXPECT_TRUE(port.prearmed());
  port.inject_strobe(1000, 10);
  port.run_until(1020);
  ASSERT_EQ(port.led_transitions().size(), 1u);
  EXPECT_EQ(port.led_transitions()[0].time_us, 1000u);  // the edge itself
  EXPECT_TRUE(listener.strobes.empty());                // not yet told
  EXPECT_TRUE(port.callbacks_pending());
  port.run_until(1025);
  ASSERT_EQ(listener.strobes.size(), 1u);
  EXPECT_EQ(listener.strobes[0].first, 1000u);  // reports the edge's time
  const PrearmStart start = port.cancel_prearm();
  EXPECT_TRUE(start.started);
  EXPECT_EQ(start.time_us, 1000u);
  EXPECT_FALSE(start.edge_pending);  // its callback ran
  port.run_until(2000);
  EXPECT_EQ(listener.table_done, std::vector<std::uint64_t>{1080});  // reports the end
  EXPECT_EQ(port.table_starts(), std::vector<std::uint64_t>{1000});
}

TEST(SimPortTiming, TheLockHoldsCallbacksNotTheHardware) {
  SimPort port(kPins);
  RecordingListener listener;
  port.set_listener(&listener);
  const std::array<std::uint32_t, 2> words = {0x00060001, 0x00070000};
  ASSERT_EQ(port.prearm_slot_table(words, 40), PortStatus::kOk);
  port.inject_strobe(1000, 10);
  port.hold_interrupts_until(1500);
  port.run_until(1200);
  EXPECT_EQ(port.led_transitions().size(), 2u);  // played and ended
  EXPECT_TRUE(listener.strobes.empty());
  // Withdrawn from the main loop under the lock: it had started; its edge's callback is to come.
  const PrearmStart start = port.cancel_prearm();
  EXPECT_TRUE(start.started);
  EXPECT_TRUE(start.edge_pending);
  port.hold_interrupts_until(0);
  port.run_until(1200);
  EXPECT_EQ(listener.strobes.size(), 2u);
  EXPECT_EQ(listener.table_done, std::vector<std::uint64_t>{1040});
}

TEST(SimPortTiming, NothingPrearmedStartsNothingAndStopDropsADoneCallback) {
  SimPort port(kPins);
  RecordingListener listener;
  port.set_listener(&listener);
  port.set_interrupt_latency_us(5);
  const std::array<std::uint32_t, 2> words = {0x00060001, 0x00070000};
  port.inject_strobe(100, 10);
  port.run_until(200);
  EXPECT_TRUE(port.led_transitions().empty());
  ASSERT_EQ(port.prearm_slot_table(words, 40), PortStatus::kOk);
  EXPECT_FALSE(port.cancel_prearm().started);
  EXPECT_FALSE(port.prearmed());
  ASSERT_EQ(port.start_slot_table(words, 40), PortStatus::kOk);
  EXPECT_EQ(port.prearm_slot_table(words, 40), PortStatus::kError);  // the DMA is busy
  port.run_until(242);  // ended at 240, its callback due at 245
  port.stop_slot_table();
  port.run_until(300);
  EXPECT_TRUE(listener.table_done.empty());
}

}  // namespace
}  // namespace flutterscan::firmware::sim
