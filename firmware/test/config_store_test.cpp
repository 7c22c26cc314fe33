// Config save/load through the virtual flash: round trip, corruption, defaults.
#include <gtest/gtest.h>

#include "flutterscan/firmware/crc32.hpp"
#include "test_rig.hpp"

namespace flutterscan::firmware::test {
namespace {

using proto::Command;
using proto::Status;

/// A rig with a non-default configuration saved to flash.
void configure_and_save(Rig& rig) {
  ASSERT_EQ(rig.upload(3, "2212441414112412441224111241244244242212442211444144", 3), Status::kOk);
  ASSERT_EQ(rig.upload(7, "101", 1), Status::kOk);
  ASSERT_EQ(rig.select(3), Status::kOk);
  ASSERT_EQ(rig.set_timing(250, 50'000, proto::SlotTimeSource::kFollowExposure), Status::kOk);
  ASSERT_EQ(rig.set_mode(proto::SyncMode::kMaster), Status::kOk);
  ASSERT_EQ(
      rig.send(Command::kSetBrightness, proto::SetBrightnessRequest{{10, 20, 30, 0}}).status(),
      Status::kOk);
  ASSERT_EQ(rig.send(Command::kSetGuard,
                     proto::SetGuardRequest{{5'000, 6'000, 7'000, 1}, {400, 500, 600, 1}})
                .status(),
            Status::kOk);
  ASSERT_EQ(rig.send(Command::kSaveConfig).status(), Status::kOk);
}

/// Rewrites the image's CRC after an edit, so only the content is wrong.
void fix_crc(std::span<std::uint8_t> flash) {
  const std::uint32_t crc = crc32(flash.first(offsetof(ConfigImage, crc32)));
  std::memcpy(flash.data() + offsetof(ConfigImage, crc32), &crc, sizeof(crc));
}

TEST(ConfigStore, SavedConfigSurvivesAReboot) {
  Rig rig;
  configure_and_save(rig);
  const auto saved = rig.settings_snapshot();
  rig.reboot();
  EXPECT_EQ(rig.settings_snapshot(), saved);
  const auto status = rig.status();
  EXPECT_EQ(status.flags & proto::kStatusConfigFromFlash, proto::kStatusConfigFromFlash);
  EXPECT_EQ(status.flags & proto::kStatusConfigCorrupt, 0);
  EXPECT_EQ(status.active_code_id, 3);
  EXPECT_EQ(status.codes_stored, 0b1000'1000);
  EXPECT_EQ(rig.port.led_brightness(2), 30);  // applied at boot
  EXPECT_EQ(rig.controller().settings().codes[7].code, LedCode::parse("101", 1).value());
  EXPECT_EQ(rig.arm(), Status::kOk);  // master, 50 ms period, stored code
}

TEST(ConfigStore, CorruptedCrcIsDetectedAndDefaultsAreUsed) {
  Rig rig;
  configure_and_save(rig);
  for (const std::size_t offset :
       {std::size_t{0}, std::size_t{13}, std::size_t{60}, sizeof(ConfigImage) - 1}) {
    SCOPED_TRACE(offset);
    rig.port.flash_page()[offset] ^= 0x10;
    rig.reboot();
    const auto status = rig.status();
    EXPECT_EQ(status.flags & proto::kStatusConfigCorrupt, proto::kStatusConfigCorrupt);
    EXPECT_EQ(status.flags & proto::kStatusConfigFromFlash, 0);
    EXPECT_EQ(status.codes_stored, 0);
    EXPECT_EQ(status.active_code_id, proto::kNoCode);
    EXPECT_EQ(status.sync_mode, static_cast<std::uint8_t>(proto::SyncMode::kSlave));
    EXPECT_EQ(status.slot_time_us, 100u);
    EXPECT_EQ(rig.port.led_brightness(0), 1000);
    rig.port.flash_page()[offset] ^= 0x10;
  }
  rig.reboot();
  EXPECT_EQ(rig.status().flags & proto::kStatusConfigFromFlash, proto::kStatusConfigFromFlash);
}

TEST(ConfigStore, DecodeNamesWhatIsWrong) {
  const BoardConfig board = test_board();
  ControllerSettings settings = default_settings(board);
  ConfigImage image = encode_config(settings);
  auto bytes = [&] {
    return std::span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>(&image),
                                         sizeof(image));
  };
  ASSERT_TRUE(decode_config(bytes(), board).ok());
  EXPECT_EQ(decode_config(bytes().first(sizeof(image) - 1), board).error(), ConfigError::kBadSize);

  ConfigImage original = image;
  image.crc32 ^= 1;
  EXPECT_EQ(decode_config(bytes(), board).error(), ConfigError::kCrcMismatch);
  image = original;
  image.magic = 0;
  EXPECT_EQ(decode_config(bytes(), board).error(), ConfigError::kBadMagic);
  image = original;
  image.format_version = 2;
  EXPECT_EQ(decode_config(bytes(), board).error(), ConfigError::kBadVersion);
  image = original;
  image.image_size = 100;
  EXPECT_EQ(decode_config(bytes(), board).error(), ConfigError::kBadSize);

  std::array<std::uint8_t, sizeof(ConfigImage)> erased;
  erased.fill(0xFF);
  EXPECT_EQ(decode_config(erased, board).error(), ConfigError::kEmpty);
}

TEST(ConfigStore, ValidCrcOverOutOfRangeContentIsRefused) {
  Rig rig;
  configure_and_save(rig);
  auto flash = rig.port.flash_page();
  const std::uint32_t zero = 0;
  std::memcpy(flash.data() + offsetof(ConfigImage, slot_time_us), &zero, sizeof(zero));
  fix_crc(flash);
  EXPECT_EQ(load_config(rig.port, test_board()).error(), ConfigError::kBadContent);
  rig.reboot();
  EXPECT_NE(rig.status().flags & proto::kStatusConfigCorrupt, 0);
  EXPECT_EQ(rig.status().codes_stored, 0);
}

TEST(ConfigStore, ACodeForMoreLedsThanTheBoardHasIsRefused) {
  Rig rig;
  configure_and_save(rig);
  BoardConfig two_leds = test_board();
  two_leds.pins = LedPinMap{2, {0, 1, 0, 0}};
  EXPECT_EQ(load_config(rig.port, two_leds).error(), ConfigError::kBadContent);
}

TEST(ConfigStore, EmptyFlashGivesDefaultsWithoutAlarm) {
  Rig rig;
  const auto status = rig.status();
  EXPECT_EQ(status.flags & (proto::kStatusConfigCorrupt | proto::kStatusConfigFromFlash), 0);
  EXPECT_EQ(load_config(rig.port, test_board()).error(), ConfigError::kEmpty);
}

// SaveConfig of settings the newest copy already holds erases nothing: each
// sector is rated for 10,000 erase cycles, and an erase masks interrupts for
// up to 2 s (issue 46, defect 5).
TEST(ConfigStore, SavingUnchangedSettingsWritesNothing) {
  Rig rig;
  ASSERT_EQ(rig.upload(2, "124", 3), Status::kOk);
  const Reply first = rig.send(Command::kSaveConfig);
  ASSERT_EQ(first.status(), Status::kOk);
  const int operations = rig.port.flash_operations();
  EXPECT_GT(operations, 0);
  for (int i = 0; i < 3; ++i) {
    const Reply again = rig.send(Command::kSaveConfig);
    ASSERT_EQ(again.status(), Status::kOk);
    EXPECT_EQ(again.as<proto::SaveConfigReply>().crc32,
              first.as<proto::SaveConfigReply>().crc32);
  }
  EXPECT_EQ(rig.port.flash_operations(), operations);
  // A change is written (into the other page), and loads after a reboot.
  ASSERT_EQ(rig.set_timing(250), Status::kOk);
  ASSERT_EQ(rig.send(Command::kSaveConfig).status(), Status::kOk);
  EXPECT_GT(rig.port.flash_operations(), operations);
  rig.reboot();
  EXPECT_EQ(rig.controller().settings().timing.slot_time_us, 250u);
}

}  // namespace
}  // namespace flutterscan::firmware::test
