// The controller commands of the real `flutterscan` binary against the
// built-in virtual controller (--device sim), and their errors: exit 0
// success, 1 runtime failure, 2 bad usage or input. Each test gets its own sim
// state file (FLUTTERSCAN_SIM_STATE), so saved settings carry over only
// within a test.

#include <fcntl.h>
#include <gtest/gtest.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

extern char** environ;

namespace {

namespace fs = std::filesystem;

constexpr const char* kCode = "2212441414112412441224111241244244242212442211444144";

struct RunResult {
  int exit_code = -1;
  std::string out;
  std::string err;
};

std::ostream& operator<<(std::ostream& stream, const RunResult& result) {
  return stream << "exit code " << result.exit_code << "\n--- stdout ---\n"
                << result.out.substr(0, 3000) << "\n--- stderr ---\n"
                << result.err.substr(0, 3000) << "\n";
}

std::string slurp(const fs::path& path) {
  std::ifstream stream(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(stream), std::istreambuf_iterator<char>()};
}

class DeviceCli : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    scratch_ = fs::temp_directory_path() /
               ("flutterscan_device_cli_" + std::to_string(::getpid()) + "_" + info->name());
    fs::remove_all(scratch_);
    fs::create_directories(scratch_);
    ::setenv("FLUTTERSCAN_SIM_STATE", (scratch_ / "sim.flash").c_str(), 1);
  }
  void TearDown() override { fs::remove_all(scratch_); }

  /// Runs the binary with `args`, stdout and stderr to files, bounded by a 30 s alarm.
  /// With `interrupt_after_ms` >= 0, sends SIGINT (Ctrl-C) once that long has passed and
  /// stdout holds `interrupt_once` (so that a slow start, under a sanitizer or a loaded
  /// machine, is not interrupted before it runs).
  RunResult run(const std::vector<std::string>& args,
                const std::string& binary = FLUTTERSCAN_BINARY, int interrupt_after_ms = -1,
                const std::string& interrupt_once = "") {
    const fs::path out = scratch_ / "stdout";
    const fs::path err = scratch_ / "stderr";
    std::vector<std::string> storage{binary};
    storage.insert(storage.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (auto& arg : storage) argv.push_back(arg.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_addopen(&actions, 1, out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
    posix_spawn_file_actions_addopen(&actions, 2, err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
    pid_t pid = 0;
    RunResult result;
    if (posix_spawn(&pid, binary.c_str(), &actions, nullptr, argv.data(), environ) != 0) {
      ADD_FAILURE() << "cannot start " << binary;
      posix_spawn_file_actions_destroy(&actions);
      return result;
    }
    posix_spawn_file_actions_destroy(&actions);
    int status = 0;
    bool interrupted = false;
    for (int waited_ms = 0;; waited_ms += 10) {
      const pid_t done = ::waitpid(pid, &status, WNOHANG);
      if (done == pid) break;
      if (!interrupted && interrupt_after_ms >= 0 && waited_ms >= interrupt_after_ms &&
          slurp(out).find(interrupt_once) != std::string::npos) {
        ::kill(pid, SIGINT);
        interrupted = true;
      }
      if (waited_ms > 30'000) {
        ::kill(pid, SIGKILL);
        ::waitpid(pid, &status, 0);
        ADD_FAILURE() << "flutterscan did not finish within 30 s";
        break;
      }
      ::usleep(10'000);
    }
    result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    result.out = slurp(out);
    result.err = slurp(err);
    return result;
  }

  static std::vector<std::string> sim(std::vector<std::string> args) {
    args.insert(args.end(), {"--device", "sim"});
    return args;
  }

  fs::path scratch_;
};

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST_F(DeviceCli, InfoDescribesTheVirtualController) {
  const auto r = run(sim({"device", "info"}));
  ASSERT_EQ(r.exit_code, 0) << r;
  EXPECT_TRUE(contains(r.out, "virtual controller")) << r;
  EXPECT_TRUE(contains(r.out, "protocol    1.1")) << r;
  EXPECT_TRUE(contains(r.out, "3 LEDs, 8 code slots")) << r;
  EXPECT_TRUE(contains(r.out, "slave-sync")) << r;
}

TEST_F(DeviceCli, StatusOfAFreshController) {
  const auto r = run(sim({"device", "status"}));
  ASSERT_EQ(r.exit_code, 0) << r;
  EXPECT_TRUE(contains(r.out, "state            idle")) << r;
  EXPECT_TRUE(contains(r.out, "codes stored     none")) << r;
}

TEST_F(DeviceCli, SetCodeSelectSaveThenMonitorArmedEvents) {
  auto r = run(sim({"device", "set-code", kCode, "--id", "2", "--select", "--save"}));
  ASSERT_EQ(r.exit_code, 0) << r;
  EXPECT_TRUE(contains(r.out, "code 2 stored: 52 slots, 3 LEDs")) << r;
  EXPECT_TRUE(contains(r.out, "code 2 selected")) << r;
  // The saved configuration comes back at the next power-on of the sim.
  r = run(sim({"device", "status"}));
  ASSERT_EQ(r.exit_code, 0) << r;
  EXPECT_TRUE(contains(r.out, "codes stored     2")) << r;
  EXPECT_TRUE(contains(r.out, "config loaded from flash")) << r;
  r = run(sim({"device", "monitor", "--arm", "--count", "5", "--sim-rate-hz", "100"}));
  ASSERT_EQ(r.exit_code, 0) << r;
  for (const char* frame : {"\n         1 ", "\n         5 "})
    EXPECT_TRUE(contains(r.out, frame)) << r;
  EXPECT_FALSE(contains(r.out, "lost before")) << r;
  EXPECT_TRUE(contains(r.err, "5 events, 0 exposures without an event")) << r;
}

TEST_F(DeviceCli, MonitorStopsCleanlyOnCtrlC) {
  ASSERT_EQ(run(sim({"device", "set-code", kCode, "--select", "--save"})).exit_code, 0);
  const auto r = run(sim({"device", "monitor", "--arm"}), FLUTTERSCAN_BINARY, 700, "\n         1 ");
  EXPECT_EQ(r.exit_code, 0) << r;
  EXPECT_TRUE(contains(r.out, "\n         1 ")) << r;
  EXPECT_TRUE(contains(r.err, "0 exposures without an event")) << r;
  // Disarmed at the end: the next power-on of the sim is idle anyway, so ask a
  // monitor without --arm, which says the controller is idle.
  const auto idle = run(sim({"device", "monitor", "--seconds", "0.2"}));
  EXPECT_EQ(idle.exit_code, 0) << idle;
  EXPECT_TRUE(contains(idle.err, "the controller is idle")) << idle;
}

TEST_F(DeviceCli, SetCodeRejectsBadInputWithExit2) {
  auto r = run(sim({"device", "set-code", "12x4"}));
  EXPECT_EQ(r.exit_code, 2) << r;
  r = run(sim({"device", "set-code", kCode, "--id", "9"}));
  EXPECT_EQ(r.exit_code, 2) << r;
  r = run(sim({"device", "set-code", "1233"}));  // two LEDs in slot 3: not one-of-N
  EXPECT_EQ(r.exit_code, 2) << r;
  r = run(sim({"device", "set-code", "1233", "--any-mask"}));
  EXPECT_EQ(r.exit_code, 0) << r;
}

TEST_F(DeviceCli, SelectCodeOfAnEmptySlotIsBadInput) {
  const auto r = run(sim({"device", "select-code", "5"}));
  EXPECT_EQ(r.exit_code, 2) << r;
  EXPECT_TRUE(contains(r.err, "SelectCode refused by the controller: no code stored")) << r;
}

TEST_F(DeviceCli, SetTimingAndItsRange) {
  auto r = run(sim({"device", "set-timing", "--slot-us", "250", "--frame-period-us", "20000"}));
  ASSERT_EQ(r.exit_code, 0) << r;
  EXPECT_TRUE(contains(r.out, "slot time 250 us, frame period 20000 us")) << r;
  r = run(sim({"device", "set-timing", "--slot-us", "0"}));
  EXPECT_EQ(r.exit_code, 2) << r;
  r = run(sim({"device", "set-timing"}));
  EXPECT_EQ(r.exit_code, 2) << r;
}

TEST_F(DeviceCli, SetModeKnowsItsModes) {
  auto r = run(sim({"device", "set-mode", "free"}));
  ASSERT_EQ(r.exit_code, 0) << r;
  r = run(sim({"device", "set-mode", "sideways"}));
  EXPECT_EQ(r.exit_code, 2) << r;
  EXPECT_TRUE(contains(r.err, "unknown mode 'sideways'")) << r;
}

TEST_F(DeviceCli, BrightnessPerLed) {
  auto r = run(sim({"device", "brightness", "1000", "500", "250"}));
  ASSERT_EQ(r.exit_code, 0) << r;
  r = run(sim({"device", "brightness", "1000", "1500", "250"}));
  EXPECT_EQ(r.exit_code, 2) << r;
  EXPECT_TRUE(contains(r.err, "brightness of LED 1: 1500 is outside 0..1000")) << r;
  r = run(sim({"device", "brightness", "1000", "500"}));
  EXPECT_EQ(r.exit_code, 2) << r;
  EXPECT_TRUE(contains(r.err, "the controller has 3 LEDs")) << r;
}

TEST_F(DeviceCli, GuardAboveTheFirmwaresCeilingIsRefusedByName) {
  auto r = run(sim({"device", "guard", "--on-time-us", "50000", "--duty-permille", "400"}));
  ASSERT_EQ(r.exit_code, 0) << r;
  r = run(sim({"device", "guard", "--on-time-us", "50000", "--duty-permille", "400", "400",
               "900"}));
  EXPECT_EQ(r.exit_code, 2) << r;
  EXPECT_TRUE(contains(r.err, "above the LED ceiling compiled into the firmware (status 14)"))
      << r;
  r = run(sim({"device", "guard", "--on-time-us", "0", "--duty-permille", "400"}));
  EXPECT_EQ(r.exit_code, 2) << r;
  EXPECT_TRUE(contains(r.err, "--on-time-us of LED 0: 0 is outside 1..2560000")) << r;
  r = run(sim({"device", "guard", "--on-time-us", "1", "2", "--duty-permille", "400"}));
  EXPECT_EQ(r.exit_code, 2) << r;
  EXPECT_TRUE(contains(r.err, "--on-time-us has 2 values, the controller has 3 LEDs")) << r;
}

TEST_F(DeviceCli, ArmWithoutACodeFailsAndDisarmAlwaysWorks) {
  auto r = run(sim({"device", "arm"}));
  EXPECT_EQ(r.exit_code, 2) << r;
  EXPECT_TRUE(contains(r.err, "Arm refused by the controller: no code stored")) << r;
  r = run(sim({"device", "disarm"}));
  EXPECT_EQ(r.exit_code, 0) << r;
  ASSERT_EQ(run(sim({"device", "set-code", kCode, "--select", "--save"})).exit_code, 0);
  r = run(sim({"device", "arm"}));
  EXPECT_EQ(r.exit_code, 0) << r;
  EXPECT_TRUE(contains(r.out, "armed")) << r;
}

TEST_F(DeviceCli, SelfTestAndSave) {
  auto r = run(sim({"device", "selftest", "--step-us", "1000"}));
  ASSERT_EQ(r.exit_code, 0) << r;
  EXPECT_TRUE(contains(r.out, "self test: 3 LEDs, 1000 us each")) << r;
  r = run(sim({"device", "selftest", "--step-us", "0"}));
  EXPECT_EQ(r.exit_code, 2) << r;
  r = run(sim({"device", "save"}));
  ASSERT_EQ(r.exit_code, 0) << r;
  EXPECT_TRUE(contains(r.out, "saved 2136 bytes")) << r;
}

TEST_F(DeviceCli, DevicesWithoutUsbControllers) {
  const auto r = run({"devices"});
  ASSERT_EQ(r.exit_code, 0) << r;
  EXPECT_TRUE(contains(r.out, "no flutterscan controller is connected")) << r;
}

TEST_F(DeviceCli, DeviceCommandWithoutControllersIsARuntimeFailure) {
  const auto r = run({"device", "info"});
  EXPECT_EQ(r.exit_code, 1) << r;
  EXPECT_TRUE(contains(r.err, "no controller in application mode is connected")) << r;
  const auto named = run({"device", "status", "--device", "0123456789ABCDEF01234567"});
  EXPECT_EQ(named.exit_code, 1) << named;
  EXPECT_TRUE(contains(named.err, "no controller with serial number 0123456789ABCDEF01234567"))
      << named;
}

TEST_F(DeviceCli, FlashRefusesBadImagesBeforeTouchingAnyDevice) {
  const fs::path junk = scratch_ / "junk.bin";
  std::ofstream(junk, std::ios::binary) << std::string(4096, 'x');
  auto r = run({"flash", junk.string()});
  EXPECT_EQ(r.exit_code, 2) << r;
  EXPECT_TRUE(contains(r.err, "no flutterscan application header")) << r;
  r = run({"flash", (scratch_ / "missing.hex").string()});
  EXPECT_EQ(r.exit_code, 2) << r;
  EXPECT_TRUE(contains(r.err, "cannot open the file")) << r;
  r = run({"flash", "--device", "sim"});
  EXPECT_EQ(r.exit_code, 2) << r;
}

TEST_F(DeviceCli, FlashAValidImageWithoutControllersIsARuntimeFailure) {
  const fs::path image = FLUTTERSCAN_FW_STM32F405_BIN;
  if (!fs::exists(image)) GTEST_SKIP() << "no fw-stm32f405 image at " << image;
  const auto r = run({"flash", image.string()});
  EXPECT_EQ(r.exit_code, 1) << r;
  EXPECT_TRUE(contains(r.err, "no controller is connected")) << r;
}

TEST_F(DeviceCli, FlashWithoutAFileUsesTheFirmwareInstalledBesideTheBinary) {
  const fs::path image = FLUTTERSCAN_FW_STM32F405_BIN;
  if (!fs::exists(image)) GTEST_SKIP() << "no fw-stm32f405 image at " << image;
  // An installed layout: PREFIX/bin/flutterscan, PREFIX/share/flutterscan/firmware/.
  const fs::path prefix = scratch_ / "prefix";
  fs::create_directories(prefix / "bin");
  fs::create_directories(prefix / "share/flutterscan/firmware");
  fs::copy_file(FLUTTERSCAN_BINARY, prefix / "bin/flutterscan");
  fs::copy_file(image, prefix / "share/flutterscan/firmware/flutterscan-fw-stm32f405.bin");
  const auto r = run({"flash"}, (prefix / "bin/flutterscan").string());
  EXPECT_EQ(r.exit_code, 1) << r;  // no controller here, but the image was found and checked
  EXPECT_TRUE(contains(r.err, (prefix / "share/flutterscan/firmware").string())) << r;
  EXPECT_TRUE(contains(r.err, "for board 1")) << r;
}

TEST_F(DeviceCli, HelpListsTheDeviceCommands) {
  const auto r = run({"device", "--help"});
  ASSERT_EQ(r.exit_code, 0) << r;
  for (const char* name : {"info", "status", "set-code", "select-code", "set-timing", "set-mode",
                           "brightness", "guard", "arm", "disarm", "selftest", "save",
                           "monitor"})
    EXPECT_TRUE(contains(r.out, name)) << name;
}

}  // namespace
