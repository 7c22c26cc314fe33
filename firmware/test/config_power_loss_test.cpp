// SaveConfig with power lost at every flash operation (issue 15, finding 7):
// the controller always boots with either the configuration saved before or
// the one being saved, never with the board's defaults.
#include <gtest/gtest.h>

#include <vector>

#include "test_rig.hpp"

namespace flutterscan::firmware::test {
namespace {

using proto::Command;
using proto::Status;

/// Settings A: a code and a 5 ms guard; B differs in the guard and brightness.
void configure(Rig& rig, std::uint32_t on_time_us, std::uint16_t brightness) {
  ASSERT_EQ(rig.upload(2, "1201", 2), Status::kOk);
  ASSERT_EQ(rig.select(2), Status::kOk);
  ASSERT_EQ(
      rig.send(Command::kSetGuard,
               proto::SetGuardRequest{{on_time_us, on_time_us, on_time_us, 1}, {400, 500, 600, 1}})
          .status(),
      Status::kOk);
  ASSERT_EQ(rig.send(Command::kSetBrightness, proto::SetBrightnessRequest{{brightness, 20, 30, 0}})
                .status(),
            Status::kOk);
}

TEST(ConfigPowerLoss, EverySaveInterruptedAtEveryFlashWriteRecovers) {
  // How many flash operations one save takes (erase, image, commit).
  int operations_per_save = 0;
  {
    Rig rig;
    configure(rig, 5'000, 100);
    const int before = rig.port.flash_operations();
    ASSERT_EQ(rig.send(Command::kSaveConfig).status(), Status::kOk);
    operations_per_save = rig.port.flash_operations() - before;
  }
  ASSERT_EQ(operations_per_save, 3);
  int cases = 0;
  // Saves 1..4 in a row (each rewrites the other page), the last interrupted.
  for (int saves_before = 0; saves_before < 4; ++saves_before) {
    for (int op = 0; op < operations_per_save; ++op) {
      for (const std::size_t bytes :
           {std::size_t{0}, std::size_t{1}, std::size_t{4}, std::size_t{15}, std::size_t{1024},
            std::size_t{2135}, std::size_t{16 * 1024}}) {
        SCOPED_TRACE(testing::Message() << saves_before << " saves, then power lost in flash "
                                        << "operation " << op << " after " << bytes << " bytes");
        Rig rig;
        std::vector<std::uint8_t> old_settings = rig.settings_snapshot();  // defaults
        for (int i = 0; i < saves_before; ++i) {
          configure(rig, 5'000 + 1'000 * static_cast<std::uint32_t>(i),
                    static_cast<std::uint16_t>(100 + i));
          ASSERT_EQ(rig.send(Command::kSaveConfig).status(), Status::kOk);
          old_settings = rig.settings_snapshot();
        }
        configure(rig, 9'999, 999);
        const std::vector<std::uint8_t> new_settings = rig.settings_snapshot();
        rig.port.lose_power_at_flash_operation(op, bytes);
        EXPECT_EQ(rig.send(Command::kSaveConfig).status(), Status::kFlashError);
        rig.port.restore_power();
        rig.reboot();
        const auto loaded = rig.settings_snapshot();
        const bool is_old = loaded == old_settings;
        const bool is_new = loaded == new_settings;
        EXPECT_TRUE(is_old || is_new);
        if (saves_before > 0) {
          // Something was saved: it (or the new one) is what loads, no alarm.
          EXPECT_NE(rig.status().flags & proto::kStatusConfigFromFlash, 0);
          EXPECT_EQ(rig.status().flags & proto::kStatusConfigCorrupt, 0);
        }
        // The device saves again normally, and that save is what loads next.
        configure(rig, 7'777, 777);
        const std::vector<std::uint8_t> again = rig.settings_snapshot();
        ASSERT_EQ(rig.send(Command::kSaveConfig).status(), Status::kOk);
        rig.reboot();
        EXPECT_EQ(rig.settings_snapshot(), again);
        ++cases;
      }
    }
  }
  EXPECT_EQ(cases, 4 * 3 * 7);
}

TEST(ConfigPowerLoss, TheNewestOfTwoValidCopiesLoads) {
  Rig rig;
  configure(rig, 5'000, 100);
  ASSERT_EQ(rig.send(Command::kSaveConfig).status(), Status::kOk);
  configure(rig, 6'000, 200);
  ASSERT_EQ(rig.send(Command::kSaveConfig).status(), Status::kOk);
  const auto second = rig.settings_snapshot();
  configure(rig, 7'000, 300);
  ASSERT_EQ(rig.send(Command::kSaveConfig).status(), Status::kOk);  // over the first
  const auto third = rig.settings_snapshot();
  rig.reboot();
  EXPECT_EQ(rig.settings_snapshot(), third);
  // Spoil the newest copy's image: the one before it loads.
  rig.port.flash_page(0)[100] ^= 0x01;
  rig.reboot();
  EXPECT_EQ(rig.settings_snapshot(), second);
}

}  // namespace
}  // namespace flutterscan::firmware::test
