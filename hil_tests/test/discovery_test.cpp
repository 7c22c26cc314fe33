// Discovery and GetInfo through the mocked USB device, with the client built
// against each hidapi backend, and through the flutterscan binary.

#include <gtest/gtest.h>

#include "hil_run.hpp"

namespace flutterscan::hil::test {
namespace {

constexpr const char* kSerial = "0123456789ABCDEF01234567";

void expect_info(const HarnessRun& run, const std::string& backend) {
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_EQ(output_value(run.output, "found"), "1") << run.output;
  EXPECT_EQ(output_value(run.output, "backend"), backend);
  EXPECT_NE(run.output.find("device mode=application serial=" + std::string(kSerial)),
            std::string::npos)
      << run.output;
  EXPECT_EQ(output_value(run.output, "protocol"), "1.1");
  EXPECT_EQ(output_value(run.output, "firmware"), "0.3.1");  // the image in the board's flash
  EXPECT_EQ(output_value(run.output, "led_count"), "3");
  // The board saw the enumeration and a GetInfo request first.
  const auto& e = run.record.at("enumerations");
  ASSERT_EQ(e.size(), 1u);
  EXPECT_TRUE(e[0].at("ok").get<bool>());
  EXPECT_EQ(e[0].at("serial"), kSerial);
  ASSERT_FALSE(run.record.at("out_reports").empty());
  EXPECT_EQ(run.record.at("out_reports")[0].at("command"), 0x01);
}

TEST(HilDiscovery, InfoThroughHidapiHidrawBackend) {
  const auto dir = make_work_dir("info_hidraw");
  const auto run = run_harness({"--serial", kSerial, "--firmware-version", "0.3.1"},
                               {HIL_CLIENT_HIDRAW, "info"}, dir);
  if (run.exit_code == 77) GTEST_SKIP() << run.output;
  expect_info(run, "hidraw");
  EXPECT_NE(output_value(run.output, "link").find("/dev/hidraw0"), std::string::npos);
}

TEST(HilDiscovery, InfoThroughHidapiLibusbBackend) {
  const auto dir = make_work_dir("info_libusb");
  const auto run = run_harness({"--serial", kSerial, "--firmware-version", "0.3.1"},
                               {HIL_CLIENT_LIBUSB, "info"}, dir);
  if (run.exit_code == 77) GTEST_SKIP() << run.output;
  expect_info(run, "libusb");
}

TEST(HilDiscovery, FlutterscanDeviceInfo) {
  const auto dir = make_work_dir("cli_info");
  const auto run = run_harness({"--serial", kSerial, "--firmware-version", "0.3.1"},
                               {FLUTTERSCAN_BINARY, "device", "info"}, dir);
  if (run.exit_code == 77) GTEST_SKIP() << run.output;
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find(kSerial), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("0.3.1"), std::string::npos) << run.output;
}

TEST(HilDiscovery, FlutterscanDevicesListsTheController) {
  const auto dir = make_work_dir("cli_devices");
  const auto run = run_harness({"--serial", kSerial}, {FLUTTERSCAN_BINARY, "devices"}, dir);
  if (run.exit_code == 77) GTEST_SKIP() << run.output;
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find(kSerial), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("application"), std::string::npos) << run.output;
}

TEST(HilDiscovery, FlutterscanDevicesSeesTheBootloader) {
  const auto dir = make_work_dir("cli_devices_dfu");
  const auto run =
      run_harness({"--serial", kSerial, "--empty-flash"}, {FLUTTERSCAN_BINARY, "devices"}, dir);
  if (run.exit_code == 77) GTEST_SKIP() << run.output;
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find(kSerial), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("DFU"), std::string::npos) << run.output;
}

}  // namespace
}  // namespace flutterscan::hil::test
