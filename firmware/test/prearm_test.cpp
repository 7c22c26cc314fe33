// Pre-armed tables on a port with the product board's timing (issue 15,
// findings 3 and 4): the SimPort starts a pre-armed table on its trigger edge
// in hardware, and delivers callbacks after an interrupt latency or the end of
// the main loop's interrupt lock. The guard must have decided before any LED
// lights, the history must hold what really lit, and no table the DMA may read
// is ever rewritten.
#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "sequence_check.hpp"
#include "test_rig.hpp"

namespace flutterscan::firmware::test {
namespace {

using proto::Command;
using proto::Status;

constexpr std::uint32_t kLatencyUs = 30;

LedCode code3(std::string_view digits) {
  return LedCode::parse(digits, 3).value();
}

// A code the guard allows only every 10 ms (10 % duty): strobes every 1 ms.
// With the pre-arm decided before the edge, every refused exposure stays
// completely dark, also with 30 us of interrupt latency; the lit ones start on
// the edge itself.
TEST(Prearm, RefusedExposuresStayDarkDespiteInterruptLatency) {
  Rig rig;
  rig.port.set_interrupt_latency_us(kLatencyUs);
  proto::SetGuardRequest guard = permissive_guard();
  guard.max_duty_permille.fill(100);
  ASSERT_EQ(rig.send(Command::kSetGuard, guard).status(), Status::kOk);
  ASSERT_EQ(rig.upload(0, "1100", 3), Status::kOk);  // LED 0: 200 us per exposure
  ASSERT_EQ(rig.select(0), Status::kOk);
  ASSERT_EQ(rig.set_timing(100, 0), Status::kOk);
  ASSERT_EQ(rig.arm(), Status::kOk);
  rig.port.clear_led_transitions();
  for (int i = 0; i < 40; ++i)
    rig.port.inject_strobe(1'000 + 1'000 * static_cast<std::uint64_t>(i), 500);
  for (std::uint64_t t = 0; t < 45'000; t += 100) {
    rig.port.run_until(t);
    rig.controller().poll();  // the main loop
  }
  const auto& log = rig.port.led_transitions();
  const auto events = rig.events();
  ASSERT_FALSE(events.empty());
  // Every lit exposure lit at a strobe edge (the pre-armed path) or later, for
  // exactly its code; every refused one lit nothing.
  int lit = 0;
  for (std::size_t i = 0; i < log.size(); ++i)
    if (log[i].led_mask != 0 && (i == 0 || log[i - 1].led_mask == 0)) ++lit;
  EXPECT_GT(lit, 1);
  EXPECT_LE(on_time_us(log, 0, 0, 45'000) * 1000, 100u * 44'000 + 200'000);
  const auto starts = rig.port.table_starts();
  for (std::size_t i = 1; i < starts.size(); ++i)
    EXPECT_GE((starts[i] - starts[i - 1]) * 100, 200u * 1000) << "starts " << i - 1 << ", " << i;
}

// Disarm in the main loop while the strobe interrupt is held off by the lock:
// the pre-armed table already started in hardware. It is cut, and what lit is
// in the history: the next exposure is judged against it.
TEST(Prearm, ATableStartedUnderTheLockIsInTheHistoryWhenDisarmCutsIt) {
  Rig rig;
  rig.port.set_interrupt_latency_us(kLatencyUs);
  proto::SetGuardRequest guard = permissive_guard();
  guard.max_duty_permille.fill(100);
  ASSERT_EQ(rig.send(Command::kSetGuard, guard).status(), Status::kOk);
  ASSERT_EQ(rig.upload(0, "1111", 3), Status::kOk);  // LED 0 on 400 us: 4 ms period
  ASSERT_EQ(rig.select(0), Status::kOk);
  ASSERT_EQ(rig.set_timing(100, 0), Status::kOk);
  ASSERT_EQ(rig.arm(), Status::kOk);
  ASSERT_TRUE(rig.port.prearmed());  // cold after power-on: accepted at once
  rig.port.inject_strobe(1'000, 50);
  rig.port.hold_interrupts_until(1'200);  // the main loop holds the lock
  rig.port.run_until(1'150);
  ASSERT_EQ(rig.port.led_mask() & 1, 1);  // started by the edge, no callback yet
  ASSERT_EQ(rig.disarm(), Status::kOk);   // ... and the main loop disarms
  EXPECT_EQ(rig.port.led_mask(), 0);
  rig.port.run_until(1'300);
  ASSERT_EQ(rig.arm(), Status::kOk);
  // 150 us lit (counted as the whole exposure, 400 us): the next needs 4 ms.
  rig.port.inject_strobe(2'000, 50);
  rig.port.inject_strobe(5'100, 50);
  rig.port.run_until(8'000);
  const auto events = rig.events();
  ASSERT_EQ(events.size(), 2u);
  EXPECT_NE(events[0].flags & proto::kEventGuardHit, 0);
  EXPECT_EQ(events[1].flags & proto::kEventGuardHit, 0);
}

// Finding 4: a SelectCode of a third code while the pending code's table is
// pre-armed (and, under the lock, already started by an edge) rebuilt that
// very table under the running DMA. The exposure must play the old pending
// code exactly and end all off; the third code plays from the next one.
TEST(Prearm, SelectingAThirdCodeNeverRewritesATableTheDmaMayRead) {
  Rig rig;
  rig.port.set_interrupt_latency_us(kLatencyUs);
  ASSERT_EQ(rig.upload(0, "100", 3), Status::kOk);
  ASSERT_EQ(rig.upload(1, "2424", 3), Status::kOk);
  ASSERT_EQ(rig.upload(2, "12412412", 3), Status::kOk);  // longer: a different all-off slot
  ASSERT_EQ(rig.select(0), Status::kOk);
  ASSERT_EQ(rig.set_timing(100, 0), Status::kOk);
  ASSERT_EQ(rig.arm(), Status::kOk);
  rig.port.inject_strobe(1'000, 50);  // code 0
  rig.port.run_until(2'000);
  ASSERT_EQ(rig.select(1), Status::kOk);  // pending, pre-armed
  ASSERT_TRUE(rig.port.prearmed());
  rig.port.clear_led_transitions();
  rig.port.inject_strobe(3'000, 50);
  rig.port.hold_interrupts_until(3'100);
  rig.port.run_until(3'050);              // the edge started code 1's table; its callback waits
  ASSERT_EQ(rig.select(2), Status::kOk);  // the main loop, under the lock
  rig.port.inject_strobe(5'000, 50);
  rig.port.run_until(4'500);
  // Code 2 right after code 1 was over the 50 % duty default; by now it is
  // not, and the main loop's poll pre-arms it: it starts on the edge.
  EXPECT_FALSE(rig.port.prearmed());
  rig.controller().poll();
  EXPECT_TRUE(rig.port.prearmed());
  rig.port.run_until(9'000);
  const auto& log = rig.port.led_transitions();
  EXPECT_TRUE(plays_code(log, 0, code3("2424"), 3'000, 100));
  EXPECT_TRUE(plays_code(log, 5, code3("12412412"), 5'000, 100));
  EXPECT_EQ(log.back().led_mask, 0);
  const auto events = rig.events();
  ASSERT_EQ(events.size(), 3u);
  EXPECT_EQ(events[1].code_id, 1);
  EXPECT_EQ(events[1].flags & proto::kEventMissedTrigger, 0);  // its own edge, not a miss
  EXPECT_EQ(events[2].code_id, 2);
  EXPECT_EQ(rig.status().missed_triggers, 0u);
}

// Follow-exposure: the slot time of the next exposure comes from the last
// pulse; a pre-armed table plays at the slot time the guard accepted.
TEST(Prearm, APrearmedTableFollowsTheMeasuredPulseWidth) {
  Rig rig;
  ASSERT_EQ(rig.upload(0, "1010", 3), Status::kOk);
  ASSERT_EQ(rig.select(0), Status::kOk);
  ASSERT_EQ(rig.set_timing(100, 0, proto::SlotTimeSource::kFollowExposure), Status::kOk);
  ASSERT_EQ(rig.arm(), Status::kOk);
  rig.port.clear_led_transitions();
  rig.port.inject_strobe(1'000, 800);  // 100 us (nothing measured yet); measures 200 us
  rig.port.inject_strobe(3'000, 400);  // 200 us slots; measures 100 us
  rig.port.inject_strobe(5'000, 400);  // 100 us slots
  rig.port.run_until(8'000);
  const auto& log = rig.port.led_transitions();
  EXPECT_TRUE(plays_code(log, 0, code3("1010"), 1'000, 100));
  EXPECT_TRUE(plays_code(log, 5, code3("1010"), 3'000, 200));
  EXPECT_TRUE(plays_code(log, 10, code3("1010"), 5'000, 100));
}

}  // namespace
}  // namespace flutterscan::firmware::test
