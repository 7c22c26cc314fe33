// Bad input and bad devices through the mocked USB device: malformed,
// truncated and oversized reports, out-of-range arguments, a device that stops
// answering, one unplugged mid-session, one speaking another protocol major.

#include <gtest/gtest.h>

#include <sstream>

#include "hil_run.hpp"

namespace flutterscan::hil::test {
namespace {

constexpr const char* kCode = "4242444412141112212414114122121114421111111122144411";

/// Statuses of the "wire_reply"/"reply" lines, in order.
std::vector<int> reply_statuses(const std::string& output, const std::string& prefix) {
  std::vector<int> out;
  std::istringstream in(output);
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind(prefix, 0) != 0) continue;
    const auto at = line.find("status=");
    if (at != std::string::npos) out.push_back(std::stoi(line.substr(at + 7)));
  }
  return out;
}

class HilMalformed : public ::testing::TestWithParam<const char*> {};

TEST_P(HilMalformed, ReportsAreRejectedAndTheDeviceKeepsWorking) {
  const std::string client = GetParam();
  const auto dir = make_work_dir("malformed");
  const std::string oversized = "01" + std::string(2 * 99, '0');  // 100 bytes: 64 + 36 on the wire
  const auto run = run_harness({},
                               {client, "wire",
                                "0100",            // truncated: GetInfo header cut to 2 bytes
                                "-",               // empty report
                                "7f000000",        // unknown command
                                "01000001",        // reserved header byte set
                                "01003d00",        // payload length 61: more than a report holds
                                "04000300000000",  // SetTiming with 3 of its 12 payload bytes
                                oversized},
                               dir);
  if (run.exit_code == 77) GTEST_SKIP() << run.output;
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const auto statuses = reply_statuses(run.output, "wire_reply");
  // One reply per packet: 6 short reports, and the oversized one arrives as a
  // valid 64-byte GetInfo followed by a 36-byte tail of zeros.
  ASSERT_EQ(statuses.size(), 8u) << run.output;
  for (std::size_t i = 0; i < 6; ++i) EXPECT_NE(statuses[i], 0) << "report " << i << " accepted";
  EXPECT_EQ(statuses[6], 0);  // the oversized write's first packet is a whole GetInfo
  EXPECT_NE(statuses[7], 0);  // its tail is rejected
  // The device still answers properly formed requests.
  EXPECT_NE(run.output.find("status_ok state="), std::string::npos) << run.output;
}

INSTANTIATE_TEST_SUITE_P(BothBackends, HilMalformed,
                         ::testing::Values(HIL_CLIENT_HIDRAW, HIL_CLIENT_LIBUSB));

TEST(HilArguments, OutOfRangeArgumentsGetErrorStatuses) {
  const auto dir = make_work_dir("bad_args");
  const auto run = run_harness({}, {HIL_CLIENT_HIDRAW, "bad-args"}, dir);
  if (run.exit_code == 77) GTEST_SKIP() << run.output;
  ASSERT_EQ(run.exit_code, 0) << run.output;
  for (const char* key : {"slot_time_0", "slot_time_too_long", "select_code_out_of_range",
                          "select_code_empty", "brightness_too_high", "arm_without_code"}) {
    const std::string value = output_value(run.output, key);
    ASSERT_FALSE(value.empty()) << key << "\n" << run.output;
    EXPECT_NE(std::stoi(value), 0) << key << " was accepted";
  }
  EXPECT_EQ(output_value(run.output, "status_ok state"), "0") << "the controller left idle";
  EXPECT_EQ(run.record.at("final").at("led_mask"), 0);
}

TEST(HilFaults, UnresponsiveDeviceTimesOutWithAMessageAndNoLedStaysOn) {
  const auto dir = make_work_dir("unresponsive");
  // GetInfo, code, select, timing, mode and Arm are answered; from the 7th request on
  // (Disarm) the firmware is hung, while the camera keeps strobing.
  const auto run = run_harness({"--unresponsive-after", "6", "--strobes", "20",
                                "--strobe-period-us", "10000", "--timeout-s", "60"},
                               {HIL_CLIENT_HIDRAW, "--reply-timeout-ms", "300", "session", "--code",
                                kCode, "--slot-us", "100", "--exposures", "5"},
                               dir);
  if (run.exit_code == 77) GTEST_SKIP() << run.output;
  EXPECT_EQ(run.exit_code, 1) << run.output;
  EXPECT_NE(run.output.find("disarm"), std::string::npos) << run.output;
  EXPECT_LT(run.seconds, 15.0) << "the host did not give up in time";
  // Every exposure the hung controller still played ended dark.
  const auto timeline = led_timeline(run.record);
  ASSERT_FALSE(timeline.empty());
  EXPECT_EQ(timeline.back().second, 0);
  EXPECT_EQ(run.record.at("final").at("led_mask"), 0);
}

TEST(HilFaults, UnresponsiveFromTheStartFailsCleanly) {
  const auto dir = make_work_dir("unresponsive_start");
  const auto run = run_harness({"--unresponsive-after", "0", "--timeout-s", "60"},
                               {FLUTTERSCAN_BINARY, "device", "info"}, dir);
  if (run.exit_code == 77) GTEST_SKIP() << run.output;
  EXPECT_EQ(run.exit_code, 1) << run.output;
  // The GetInfo write is swallowed, the next ones NAK until hidraw's write times out.
  EXPECT_NE(run.output.find("timed out"), std::string::npos) << run.output;
  EXPECT_LT(run.seconds, 15.0);
  EXPECT_EQ(run.record.at("final").at("led_mask"), 0);
}

TEST(HilFaults, UnplugMidSessionIsReportedWithAMessage) {
  const auto dir = make_work_dir("unplug");
  // Unplugged when the 6th request (Arm, after GetInfo and four settings) arrives.
  const auto run = run_harness({"--unplug-after", "6", "--timeout-s", "60"},
                               {HIL_CLIENT_HIDRAW, "--reply-timeout-ms", "300", "session", "--code",
                                kCode, "--slot-us", "100", "--exposures", "5"},
                               dir);
  if (run.exit_code == 77) GTEST_SKIP() << run.output;
  EXPECT_EQ(run.exit_code, 1) << run.output;
  EXPECT_NE(run.output.find("arm"), std::string::npos) << run.output;
  EXPECT_LT(run.seconds, 15.0);
  EXPECT_FALSE(run.record.at("final").at("plugged_in").get<bool>());
}

TEST(HilFaults, MonitorSurvivesAnUnplugAndLeavesTheLedsOff) {
  const auto dir = make_work_dir("unplug_monitor");
  // flutterscan device monitor --arm: unplugged after 20 exposure events, back
  // 300 ms later (a power cycle: the saved code comes back from flash); the
  // client re-opens the same serial number, re-arms and says so.
  const std::string script = std::string(FLUTTERSCAN_BINARY) + " device set-code " + kCode +
                             " --select --save && " + FLUTTERSCAN_BINARY +
                             " device monitor --arm --seconds 3";
  const auto run = run_harness({"--unplug-after-events", "20", "--replug-after-ms", "300",
                                "--strobes", "200", "--timeout-s", "60"},
                               {"/bin/sh", "-c", script}, dir);
  if (run.exit_code == 77) GTEST_SKIP() << run.output;
  EXPECT_EQ(run.exit_code, 0) << run.output;
  EXPECT_LT(run.seconds, 20.0);
  EXPECT_NE(run.output.find("waiting for it to come back"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("is back"), std::string::npos) << run.output;
  bool unplugged = false, back = false;
  for (const auto& e : run.record.at("events")) {
    const std::string what = e.at("what");
    unplugged = unplugged || what.find("unplugged") != std::string::npos;
    back = back || what.find("plugged back in") != std::string::npos;
  }
  EXPECT_TRUE(unplugged && back) << run.record.at("events").dump();
  // Events kept coming after the re-plug, and the monitor disarmed at the end.
  EXPECT_GT(exposure_events(run.record).size(), 40u);
  EXPECT_EQ(run.record.at("final").at("led_mask"), 0);
  EXPECT_EQ(run.record.at("out_reports").back().at("command"), 0x08) << "last request not Disarm";
}

TEST(HilProtocol, MajorMismatchGivesTheActionableMessage) {
  const auto dir = make_work_dir("major");
  const auto run =
      run_harness({"--protocol-major", "2"}, {FLUTTERSCAN_BINARY, "device", "info"}, dir);
  if (run.exit_code == 77) GTEST_SKIP() << run.output;
  EXPECT_NE(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("firmware speaks protocol 2"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("flutterscan flash"), std::string::npos) << run.output;
}

TEST(HilProtocol, MajorMismatchRefusedByTheLibusbBackendClient) {
  const auto dir = make_work_dir("major_libusb");
  const auto run = run_harness({"--protocol-major", "7"}, {HIL_CLIENT_LIBUSB, "info"}, dir);
  if (run.exit_code == 77) GTEST_SKIP() << run.output;
  EXPECT_EQ(run.exit_code, 1) << run.output;
  EXPECT_NE(run.output.find("protocol 7"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("flutterscan flash"), std::string::npos) << run.output;
}

}  // namespace
}  // namespace flutterscan::hil::test
