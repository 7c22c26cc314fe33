// Flashing through the mocked USB device: `flutterscan flash` and stock
// dfu-util against the firmware's own DFU runtime and bootloader (detach,
// re-enumeration as PID 0x0002, download, manifest, back to the application),
// a download cut at a random block, and images refused before any write.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "hil_run.hpp"

namespace flutterscan::hil::test {
namespace {

constexpr std::size_t kImageSize = 24 * 1024;  // 24 blocks of 1 KiB

std::string make_image(const std::string& dir, const std::string& name,
                       std::vector<std::string> options = {}) {
  const std::string path = dir + "/" + name;
  std::vector<std::string> argv{HIL_MAKE_IMAGE, path, "--size", std::to_string(kImageSize)};
  argv.insert(argv.end(), options.begin(), options.end());
  const auto [code, output] = run_plain(argv);
  EXPECT_EQ(code, 0) << output;
  return path;
}

int count_requests(const nlohmann::json& record, const std::string& request) {
  int n = 0;
  for (const auto& r : record.at("dfu_requests")) n += r.at("request") == request;
  return n;
}

/// The board runs the application again, now version 0.2.0 (bcdDevice 0x0020),
/// after a download in blocks of `transfer` bytes.
void expect_flashed(const HarnessRun& run, std::size_t transfer = 1024) {
  const auto& final = run.record.at("final");
  EXPECT_EQ(final.at("mode"), "application") << run.output;
  EXPECT_EQ(final.at("bcd_device"), 0x0020) << run.output;
  EXPECT_EQ(final.at("writes_below_app_region"), 0) << "the bootloader's sectors were touched";
  // Detach -> bootloader with the same serial -> application again.
  const auto& e = run.record.at("enumerations");
  ASSERT_GE(e.size(), 3u) << e.dump();
  EXPECT_EQ(e[1].at("mode"), "bootloader");
  EXPECT_EQ(e[1].at("serial"), e[0].at("serial"));
  EXPECT_EQ(e.back().at("mode"), "application");
  // One DNLOAD per block (the last one shorter), then the zero-length one.
  EXPECT_EQ(count_requests(run.record, "DNLOAD"),
            static_cast<int>((kImageSize + transfer - 1) / transfer) + 1);
}

/// Stock dfu-util flashes a new image through detach, download and manifest,
/// in blocks of `transfer` bytes (its -t; 0: its default, the bootloader's
/// 1024), in work directory `name`.
void expect_dfu_util_flashes(const std::string& name, std::size_t transfer = 0) {
  const auto dir = make_work_dir(name);
  const auto image = make_image(dir, "app020.bin");
  std::vector<std::string> dfu_util{DFU_UTIL, "-d", "1209:0001,1209:0002", "-D", image, "-R"};
  if (transfer != 0) dfu_util.insert(dfu_util.begin() + 3, {"-t", std::to_string(transfer)});
  const auto run = run_harness({"--timeout-s", "90"}, dfu_util, dir);
  if (run.exit_code == 77) GTEST_SKIP() << run.output;
  // dfu-util 0.11 returns libusb's LIBUSB_ERROR_NOT_FOUND (-5 -> 251) when the
  // final reset makes the device re-enumerate as the application, as it does
  // with real hardware; "Done!" says the download and manifest succeeded.
  EXPECT_TRUE(run.exit_code == 0 || run.exit_code == 251) << run.output;
  EXPECT_NE(run.output.find("Done!"), std::string::npos) << run.output;
  expect_flashed(run, transfer == 0 ? 1024 : transfer);
}

TEST(HilFlash, DfuUtilDownloadsThroughDetachAndManifest) {
  expect_dfu_util_flashes("dfu_util");
}

// Issue 15 finding 8: the bootloader placed block n at n x 1024, so a host
// using a smaller transfer size (dfu-util -t 512) left gaps and was refused at
// the manifest. Blocks now go where the bytes received so far end.
TEST(HilFlash, DfuUtilWith512ByteTransfersDownloadsAContiguousImage) {
  expect_dfu_util_flashes("dfu_util_t512", 512);
}

// Issue 46 defect 6: with -t 1022 every block after the first starts at an
// address that is not a multiple of 4, which the product's flash programming
// refuses (and now the simulated flash too); the bootloader programs whole words.
TEST(HilFlash, DfuUtilWith1022ByteTransfersDownloadsTheImage) {
  expect_dfu_util_flashes("dfu_util_t1022", 1022);
}

TEST(HilFlash, FlutterscanFlashUpdatesTheApplication) {
  const auto dir = make_work_dir("cli_flash");
  const auto image = make_image(dir, "app020.bin");
  const auto run = run_harness({"--timeout-s", "90"}, {FLUTTERSCAN_BINARY, "flash", image}, dir);
  if (run.exit_code == 77) GTEST_SKIP() << run.output;
  ASSERT_EQ(run.exit_code, 0) << run.output;
  expect_flashed(run);
}

TEST(HilFlash, InterruptedFlashLeavesDfuModeAndASecondFlashSucceeds) {
  const auto dir = make_work_dir("cli_flash_cut");
  const auto image = make_image(dir, "app020.bin");
  std::random_device rd;
  const int block = std::uniform_int_distribution<int>(1, kImageSize / 1024 - 2)(rd);
  std::cout << "power cut at DFU block " << block << "\n";
  const std::string flash = std::string(FLUTTERSCAN_BINARY) + " flash " + image;
  // The user plugs it back in (300 ms) and runs the same command again.
  const std::string script =
      flash + "; echo first_exit=$?; sleep 1; " + flash + "; echo second_exit=$?";
  const auto run = run_harness({"--unplug-at-block", std::to_string(block), "--replug-after-ms",
                                "300", "--timeout-s", "120"},
                               {"/bin/sh", "-c", script}, dir);
  if (run.exit_code == 77) GTEST_SKIP() << run.output;
  EXPECT_NE(output_value(run.output, "first_exit"), "0") << run.output;
  EXPECT_EQ(output_value(run.output, "second_exit"), "0") << run.output;
  bool cut = false, back_in_dfu = false;
  for (const auto& e : run.record.at("events")) {
    const std::string what = e.at("what");
    cut = cut || what == "power lost at DFU block " + std::to_string(block);
    back_in_dfu = back_in_dfu || what == "plugged back in: bootloader mode";
  }
  EXPECT_TRUE(cut) << run.record.at("events").dump();
  EXPECT_TRUE(back_in_dfu) << "the half-written image was started: "
                           << run.record.at("events").dump();
  EXPECT_EQ(run.record.at("final").at("mode"), "application");
  EXPECT_EQ(run.record.at("final").at("bcd_device"), 0x0020);
  EXPECT_EQ(run.record.at("final").at("writes_below_app_region"), 0);
}

// Issue 15: an image that never confirms itself (it hangs before USB, so the
// watchdog resets it) brings the board back to DFU mode by itself after three
// starts, and `flutterscan flash` then recovers it without a detach.
TEST(HilFlash, AnImageThatNeverConfirmsEndsInDfuModeAndFlutterscanFlashRecoversIt) {
  const auto dir = make_work_dir("cli_flash_recover");
  const auto image = make_image(dir, "app020.bin");
  const auto run = run_harness({"--hangs-before-usb", "--timeout-s", "90"},
                               {FLUTTERSCAN_BINARY, "flash", image}, dir);
  if (run.exit_code == 77) GTEST_SKIP() << run.output;
  ASSERT_EQ(run.exit_code, 0) << run.output;
  std::vector<std::string> resets;
  for (const auto& e : run.record.at("events")) {
    const std::string what = e.at("what");
    if (what.rfind("watchdog reset: ", 0) == 0) resets.push_back(what);
  }
  EXPECT_EQ(resets, (std::vector<std::string>{"watchdog reset: application mode",
                                              "watchdog reset: application mode",
                                              "watchdog reset: bootloader mode"}))
      << run.record.at("events").dump();
  const auto& e = run.record.at("enumerations");
  ASSERT_GE(e.size(), 2u) << e.dump();
  EXPECT_EQ(e.front().at("mode"), "bootloader");  // the host first sees DFU mode
  EXPECT_EQ(e.back().at("mode"), "application");
  const auto& final = run.record.at("final");
  EXPECT_EQ(final.at("mode"), "application") << run.output;
  EXPECT_EQ(final.at("bcd_device"), 0x0020) << run.output;
  EXPECT_EQ(final.at("writes_below_app_region"), 0);
  EXPECT_EQ(count_requests(run.record, "DNLOAD"), static_cast<int>(kImageSize / 1024) + 1);
}

// The recovery pin (PB2) held at power-on keeps DFU mode over a good image,
// and still held through the reset after a flash it keeps it again:
// `flutterscan flash` then waits in vain for the application and says so.
// Released (after that second boot), the next flash's reset starts the image.
TEST(HilFlash, TheRecoveryPinKeepsDfuModeUntilReleasedThenAFlashStartsTheApplication) {
  const auto dir = make_work_dir("cli_flash_recovery_pin");
  const auto image = make_image(dir, "app020.bin");
  const std::string flash = std::string(FLUTTERSCAN_BINARY) + " flash --wait-s 2 '" + image + "'";
  const auto run =
      run_harness({"--recovery-pin-boots", "2", "--timeout-s", "90"},
                  {"sh", "-c", flash + "; echo \"first flash: exit $?\"; " + flash}, dir);
  if (run.exit_code == 77) GTEST_SKIP() << run.output;
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("did not appear in application mode"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("first flash: exit "), std::string::npos) << run.output;
  EXPECT_EQ(run.output.find("first flash: exit 0"), std::string::npos) << run.output;
  const auto& events = run.record.at("events");
  ASSERT_FALSE(events.empty());
  EXPECT_EQ(events.front().at("what"), "power on in bootloader mode (recovery pin held)");
  int released = 0;
  for (const auto& e : events) released += e.at("what") == "recovery pin released";
  EXPECT_EQ(released, 1) << events.dump();
  // DFU mode at power-on over the good 0.1.0 image, DFU mode again after the
  // first flash's reset, then the new image.
  const auto& e = run.record.at("enumerations");
  ASSERT_EQ(e.size(), 3u) << e.dump();
  EXPECT_EQ(e[0].at("mode"), "bootloader");
  EXPECT_EQ(e[1].at("mode"), "bootloader");
  EXPECT_EQ(e[2].at("mode"), "application");
  const auto& final = run.record.at("final");
  EXPECT_EQ(final.at("mode"), "application") << run.output;
  EXPECT_EQ(final.at("bcd_device"), 0x0020) << run.output;
  EXPECT_EQ(final.at("writes_below_app_region"), 0);
  EXPECT_EQ(count_requests(run.record, "DNLOAD"), 2 * (static_cast<int>(kImageSize / 1024) + 1));
}

TEST(HilFlash, FlutterscanFlashWithoutAFileFlashesTheBuiltProductImage) {
  // `flutterscan flash` with no file flashes the fw-stm32f405 image built with
  // it; the board (running 0.0.9) ends up holding exactly that image's bytes.
  const std::string bin = FLUTTERSCAN_FW_STM32F405_BIN;
  if (!std::filesystem::exists(bin))
    GTEST_SKIP() << "no fw-stm32f405 build at " << bin << " (make fw-stm32f405; make test does)";
  const auto dir = make_work_dir("cli_flash_default");
  const auto run = run_harness({"--firmware-version", "0.0.9", "--timeout-s", "120"},
                               {FLUTTERSCAN_BINARY, "flash"}, dir);
  if (run.exit_code == 77) GTEST_SKIP() << run.output;
  ASSERT_EQ(run.exit_code, 0) << run.output;
  std::ifstream in(bin, std::ios::binary);
  std::vector<unsigned char> head(64);
  in.read(reinterpret_cast<char*>(head.data()), 64);
  std::string hex;
  char b[3];
  for (unsigned char v : head) {
    std::snprintf(b, sizeof b, "%02x", v);
    hex += b;
  }
  EXPECT_EQ(run.record.at("final").at("app_region_head"), hex);
  EXPECT_EQ(run.record.at("final").at("mode"), "application");
  EXPECT_NE(run.record.at("final").at("bcd_device"), 0x0009);
}

class HilFlashRefused : public ::testing::TestWithParam<std::vector<std::string>> {};

TEST_P(HilFlashRefused, BadImageIsRefusedBeforeAnyWrite) {
  const auto dir = make_work_dir("cli_flash_refused");
  const auto image = make_image(dir, "bad.bin", GetParam());
  const auto run = run_harness({"--timeout-s", "60"}, {FLUTTERSCAN_BINARY, "flash", image}, dir);
  if (run.exit_code == 77) GTEST_SKIP() << run.output;
  EXPECT_EQ(run.exit_code, 2) << run.output;
  EXPECT_NE(run.output.find(image), std::string::npos) << "the message names the file";
  // Not even detached: no DFU request reached the board, it still runs 0.1.x.
  EXPECT_TRUE(run.record.at("dfu_requests").empty()) << run.record.at("dfu_requests").dump();
  EXPECT_EQ(run.record.at("enumerations").size(), 1u);
  EXPECT_EQ(run.record.at("final").at("mode"), "application");
}

INSTANTIATE_TEST_SUITE_P(WrongBoardAndCorrupt, HilFlashRefused,
                         ::testing::Values(std::vector<std::string>{"--board-id", "99"},
                                           std::vector<std::string>{"--corrupt"}));

}  // namespace
}  // namespace flutterscan::hil::test
