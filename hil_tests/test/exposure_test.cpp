// Exposures through the mocked USB device: a code, a slot time, Arm, then
// simulated camera strobes; the board's LED record is checked slot by slot and
// the host's exposure events against what the board saw.

#include <gtest/gtest.h>

#include <bit>
#include <map>
#include <sstream>

#include "hil_run.hpp"

namespace flutterscan::hil::test {
namespace {

// Two one-of-3 codes of 52 slots (fixed pseudo-random digits 1, 2, 4).
constexpr const char* kCodeA = "4242444412141112212414114122121114421111111122144411";
constexpr const char* kCodeB = "1241242142411214241142124121414212142411242142141421";
constexpr std::uint64_t kSlotUs = 100;
constexpr int kStrobes = 100;
constexpr int kEncoderBase = 10;

/// Host-side event lines: frame -> (code, delta, slot_us).
struct HostEvent {
  int code = -1;
  long delta = 0;
  long slot_us = 0;
};
std::map<int, HostEvent> host_events(const std::string& output) {
  std::map<int, HostEvent> out;
  std::istringstream in(output);
  std::string line;
  while (std::getline(in, line)) {
    int frame = 0, code = 0;
    long slot = 0, delta = 0;
    if (std::sscanf(line.c_str(), "event frame=%d code=%d slot_us=%ld slots=%*d delta=%ld", &frame,
                    &code, &slot, &delta) == 4)
      out[frame] = {code, delta, slot};
  }
  return out;
}

/// Checks exposure `i`'s LED record against `code`: each slot lights its
/// digit's LED (exactly one), writes only on slot boundaries, dark after.
void expect_exposure_plays(const std::vector<std::pair<std::uint64_t, std::uint8_t>>& timeline,
                           std::uint64_t start, const std::string& code, int i) {
  const auto masks = code_masks(code);
  const std::uint64_t end = start + masks.size() * kSlotUs;
  EXPECT_EQ(mask_at(timeline, start - 1), 0) << "LEDs on before exposure " << i;
  for (std::size_t k = 0; k < masks.size(); ++k) {
    const std::uint8_t m = mask_at(timeline, start + k * kSlotUs + kSlotUs / 2);
    ASSERT_EQ(m, masks[k]) << "exposure " << i << " slot " << k;
    ASSERT_EQ(std::popcount(m), 1) << "exposure " << i << " slot " << k;
  }
  EXPECT_EQ(mask_at(timeline, end), 0) << "LEDs still on after exposure " << i;
  for (const auto& [t, m] : timeline) {
    if (t >= start && t <= end) {
      ASSERT_EQ((t - start) % kSlotUs, 0u) << "write off the slot grid in exposure " << i;
    }
  }
}

/// No LED is on outside the exposures' windows.
void expect_dark_between(const std::vector<std::pair<std::uint64_t, std::uint8_t>>& timeline,
                         const std::vector<std::uint64_t>& starts, std::uint64_t length_us) {
  for (const auto& [t, m] : timeline) {
    if (m == 0) continue;
    bool inside = false;
    for (std::uint64_t s : starts) inside = inside || (t >= s && t < s + length_us);
    EXPECT_TRUE(inside) << "LED mask " << int{m} << " at " << t << " us outside every exposure";
  }
}

TEST(HilExposure, HundredStrobesPlayTheCodeAndReachTheHost) {
  const auto dir = make_work_dir("strobes");
  const auto run =
      run_harness({"--strobes", std::to_string(kStrobes), "--strobe-width-us", "1000",
                   "--strobe-period-us", "10000", "--encoder-in-exposure",
                   std::to_string(kEncoderBase), "--encoder-between", "1000", "--timeout-s", "60"},
                  {HIL_CLIENT_HIDRAW, "session", "--code", kCodeA, "--slot-us",
                   std::to_string(kSlotUs), "--exposures", std::to_string(kStrobes)},
                  dir);
  if (run.exit_code == 77) GTEST_SKIP() << run.output;
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const auto& strobes = run.record.at("strobes");
  ASSERT_EQ(strobes.size(), static_cast<std::size_t>(kStrobes));
  const auto timeline = led_timeline(run.record);
  std::vector<std::uint64_t> starts;
  for (int i = 0; i < kStrobes; ++i) {
    const std::uint64_t start = strobes[i].at("start_us").get<std::uint64_t>();
    starts.push_back(start);
    expect_exposure_plays(timeline, start, kCodeA, i);
  }
  expect_dark_between(timeline, starts, 52 * kSlotUs);
  EXPECT_EQ(run.record.at("final").at("led_mask"), 0);

  // What the board sent: 100 events, counters 1..100, its strobe's start and encoder counts.
  const auto events = exposure_events(run.record);
  ASSERT_EQ(events.size(), static_cast<std::size_t>(kStrobes));
  for (int i = 0; i < kStrobes; ++i) {
    EXPECT_EQ(events[i].at("frame_counter"), i + 1);
    EXPECT_EQ(events[i].at("start_time_us"), starts[i]);
    EXPECT_EQ(events[i].at("slot_time_us"), kSlotUs);
    EXPECT_EQ(events[i].at("encoder_delta"), kEncoderBase + i) << "counts between exposures leak";
  }
  // What the host received: the same 100 events, no gap.
  const auto host = host_events(run.output);
  ASSERT_EQ(host.size(), static_cast<std::size_t>(kStrobes)) << run.output;
  for (int i = 0; i < kStrobes; ++i) {
    ASSERT_TRUE(host.count(i + 1)) << "frame " << i + 1 << " missing on the host";
    EXPECT_EQ(host.at(i + 1).delta, kEncoderBase + i);
    EXPECT_EQ(host.at(i + 1).slot_us, static_cast<long>(kSlotUs));
    EXPECT_EQ(host.at(i + 1).code, 0);
  }
  EXPECT_EQ(output_value(run.output, "frames_missing"), "0");
}

TEST(HilExposure, FlutterscanMonitorReceivesEveryExposure) {
  const auto dir = make_work_dir("cli_monitor");
  const std::string cli = FLUTTERSCAN_BINARY;
  const std::string script = cli + " device set-code " + kCodeB + " --select && " + cli +
                             " device set-timing --slot-us " + std::to_string(kSlotUs) + " && " +
                             cli + " device monitor --arm --seconds 20 --count " +
                             std::to_string(kStrobes);
  const auto run =
      run_harness({"--strobes", std::to_string(kStrobes), "--encoder-in-exposure",
                   std::to_string(kEncoderBase), "--encoder-between", "500", "--timeout-s", "60"},
                  {"/bin/sh", "-c", script}, dir);
  if (run.exit_code == 77) GTEST_SKIP() << run.output;
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("100 events, 0 exposures without an event"), std::string::npos)
      << run.output;
  // Frame i's line carries its encoder delta (+10 + i - 1).
  for (int frame : {1, 50, 100}) {
    std::ostringstream delta;
    delta << "+" << kEncoderBase + frame - 1;
    std::istringstream in(run.output);
    std::string line;
    bool seen = false;
    while (std::getline(in, line)) {
      std::istringstream fields(line);
      int f = 0;
      if ((fields >> f) && f == frame) seen = line.find(delta.str()) != std::string::npos;
    }
    EXPECT_TRUE(seen) << "frame " << frame << " without delta " << delta.str();
  }
  const auto& strobes = run.record.at("strobes");
  ASSERT_EQ(strobes.size(), static_cast<std::size_t>(kStrobes));
  const auto timeline = led_timeline(run.record);
  for (int i = 0; i < kStrobes; ++i)
    expect_exposure_plays(timeline, strobes[i].at("start_us").get<std::uint64_t>(), kCodeB, i);
  EXPECT_EQ(run.record.at("final").at("led_mask"), 0);
  EXPECT_EQ(run.record.at("out_reports").back().at("command"), 0x08) << "not disarmed at the end";
}

TEST(HilExposure, CodeSwitchBetweenExposuresWhileArmed) {
  const auto dir = make_work_dir("switch");
  const int strobes_n = 40;
  const auto run = run_harness(
      {"--strobes", std::to_string(strobes_n), "--strobe-width-us", "1000", "--strobe-period-us",
       "10000", "--timeout-s", "60"},
      {HIL_CLIENT_HIDRAW, "session", "--code", kCodeA, "--switch-code", kCodeB, "--switch-after",
       "15", "--slot-us", std::to_string(kSlotUs), "--exposures", std::to_string(strobes_n)},
      dir);
  if (run.exit_code == 77) GTEST_SKIP() << run.output;
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const auto events = exposure_events(run.record);
  ASSERT_EQ(events.size(), static_cast<std::size_t>(strobes_n));
  const auto& strobes = run.record.at("strobes");
  const auto timeline = led_timeline(run.record);
  int previous_code = 0;
  int switched_at = -1;
  for (int i = 0; i < strobes_n; ++i) {
    const int code = events[i].at("code_id").get<int>();
    ASSERT_GE(code, previous_code) << "code went back at exposure " << i;
    if (code == 1 && switched_at < 0) switched_at = i;
    previous_code = code;
    // Every exposure plays exactly the code its event names: never half of each.
    expect_exposure_plays(timeline, strobes[i].at("start_us").get<std::uint64_t>(),
                          code == 0 ? kCodeA : kCodeB, i);
  }
  // Selected after the host saw 15 events: exposure 16 at the earliest (how much
  // later depends on the host's scheduling; on an idle machine it is the next one).
  EXPECT_GE(switched_at, 15);
  EXPECT_LT(switched_at, strobes_n) << "the second code never played";
}

}  // namespace
}  // namespace flutterscan::hil::test
