// The boot path (issue 15, findings 5 and 6): the bootloader starts only an
// image whose jump it can use, and falls back to DFU mode by itself when an
// application does not confirm it works (hang, watchdog resets, no USB), or
// when the recovery pin is held.
#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "flutterscan/common/crc32.hpp"
#include "flutterscan/firmware/boot_decision.hpp"
#include "flutterscan/firmware/sim/sim_board.hpp"
#include "usb_test_host.hpp"

namespace flutterscan::firmware::test {
namespace {

constexpr AppRegion kRegion = kStm32f405AppRegion;

std::vector<std::uint8_t> region_with(const std::vector<std::uint8_t>& image) {
  std::vector<std::uint8_t> region(kRegion.max_size, 0xFF);
  std::copy(image.begin(), image.end(), region.begin());
  return region;
}

std::vector<std::uint8_t> good_image() {
  return sim::make_application_image(kBoardIdStm32f405, 1, 0, 0, 9000, 7);
}

void put_word(std::vector<std::uint8_t>& image, std::size_t at, std::uint32_t value) {
  std::memcpy(image.data() + at, &value, sizeof value);
}

/// Re-stamps after an edit, so only what the edit changed is wrong.
std::vector<std::uint8_t> restamped(std::vector<std::uint8_t> image) {
  EXPECT_TRUE(stamp_image(image));
  return image;
}

TEST(BootImage, AGoodImagePasses) {
  EXPECT_EQ(check_boot_image(region_with(good_image()), kRegion), BootImageCheck::kOk);
}

// Finding 5: check_image accepted any 512-aligned vector table offset (the CRC
// then covers [offset, size) only), while the jump always reads base + 0x200.
TEST(BootImage, AVectorTableElsewhereThanTheJumpIsRefused) {
  auto image = good_image();
  ImageHeader h = read_image_header(image);
  h.vector_table_offset = 0x400;  // 0x200..0x400 now outside the CRC
  std::memcpy(image.data(), &h, sizeof h);
  image = restamped(image);
  ASSERT_EQ(check_image(region_with(image), kRegion.board_id, kRegion.max_size), ImageCheck::kOk);
  // A flipped reset vector at 0x204 is no longer covered by any CRC.
  image[0x204] ^= 0x40;
  EXPECT_EQ(check_image(region_with(image), kRegion.board_id, kRegion.max_size), ImageCheck::kOk);
  EXPECT_EQ(check_boot_image(region_with(image), kRegion), BootImageCheck::kWrongVectorOffset);
  EXPECT_EQ(choose_boot_target(false, region_with(image), kRegion), BootTarget::kDfuMode);
}

TEST(BootImage, AnImageLinkedForAnotherAddressIsRefused) {
  const auto image = sim::make_application_image(kBoardIdStm32f405, 1, 0, 0, 9000, 7, 0x08010000);
  ASSERT_EQ(check_image(region_with(image), kRegion.board_id, kRegion.max_size), ImageCheck::kOk);
  EXPECT_EQ(check_boot_image(region_with(image), kRegion), BootImageCheck::kWrongLoadAddress);
}

TEST(BootImage, StackPointerAndResetVectorAreRangeChecked) {
  struct Case {
    std::uint32_t sp;
    std::uint32_t pc;
    BootImageCheck expected;
  };
  const std::uint32_t code = kRegion.load_address + 0x208 + 1;
  for (const Case c : {
           Case{0x20020000, code, BootImageCheck::kOk},
           Case{0x20010000, code, BootImageCheck::kOk},
           Case{0x20020004, code, BootImageCheck::kBadStackPointer},       // past SRAM
           Case{0x20000000, code, BootImageCheck::kBadStackPointer},       // empty stack
           Case{0x2001FFFC, code, BootImageCheck::kBadStackPointer},       // not 8-aligned
           Case{0x08008000, code, BootImageCheck::kBadStackPointer},       // flash
           Case{0xFFFFFFFF, code, BootImageCheck::kBadStackPointer},       // erased
           Case{0x20020000, code - 1, BootImageCheck::kBadResetVector},    // ARM state
           Case{0x20020000, 0x08000101, BootImageCheck::kBadResetVector},  // bootloader
           Case{0x20020000, kRegion.load_address + 0x201, BootImageCheck::kBadResetVector},
           Case{0x20020000, kRegion.load_address + 9000 + 1, BootImageCheck::kBadResetVector},
           Case{0x20020000, 0xFFFFFFFF, BootImageCheck::kBadResetVector},
       }) {
    SCOPED_TRACE(testing::Message() << std::hex << c.sp << " " << c.pc);
    auto image = good_image();
    put_word(image, 0x200, c.sp);
    put_word(image, 0x204, c.pc);
    EXPECT_EQ(check_boot_image(region_with(restamped(image)), kRegion), c.expected);
  }
}

TEST(BootImage, DfuModeRefusesAtTheManifestWhatTheBootloaderWouldNotStart) {
  sim::SimBoard board;
  ASSERT_EQ(board.mode(), sim::BoardMode::kBootloader);
  enumerate_or_fail(board);
  auto image = good_image();
  put_word(image, 0x204, 0x08000101);  // a reset vector into the bootloader
  image = restamped(image);
  ASSERT_EQ(check_image(image, kRegion.board_id, kRegion.max_size), ImageCheck::kOk);
  const DownloadLog log = dfu_download(board, image);
  ASSERT_FALSE(log.dnload_stalled);
  EXPECT_EQ(log.final_status.state, DfuState::kError);
  EXPECT_EQ(log.final_status.status, DfuStatus::kErrFirmware);
  board.bus_reset();
  EXPECT_EQ(board.mode(), sim::BoardMode::kBootloader);
  // The same image with a good reset vector manifests and starts.
  enumerate_or_fail(board);
  const DownloadLog good = dfu_download(board, good_image());
  EXPECT_EQ(good.final_status.state, DfuState::kDfuIdle);
  board.bus_reset();
  EXPECT_EQ(board.mode(), sim::BoardMode::kApplication);
}

// Finding 6: a CRC-valid application that hangs before USB had no way back.
TEST(BootRecovery, UnconfirmedStartsEndInDfuMode) {
  BootInputs in;
  in.image = BootImageCheck::kOk;
  BootRecord record{};  // power-on: random SRAM, here zeros: not a valid record
  std::vector<BootTarget> targets;
  for (int reset = 0; reset < 6; ++reset) {
    in.unconfirmed_starts = unconfirmed_starts(record);
    const BootDecision d = decide_boot(in);
    targets.push_back(d.target);
    record = make_boot_record(d.unconfirmed_starts);
    // The application hangs (watchdog reset) before it confirms: nothing clears the record.
  }
  EXPECT_EQ(targets, (std::vector<BootTarget>{BootTarget::kApplication, BootTarget::kApplication,
                                              BootTarget::kApplication, BootTarget::kDfuMode,
                                              BootTarget::kDfuMode, BootTarget::kDfuMode}));
  // The application confirms itself: the next resets start it again.
  record = make_boot_record(0);
  in.unconfirmed_starts = unconfirmed_starts(record);
  EXPECT_EQ(decide_boot(in).target, BootTarget::kApplication);
}

TEST(BootRecovery, APowerOnRecordOrACorruptOneCountsNothing) {
  EXPECT_EQ(unconfirmed_starts(BootRecord{0, 0, 0}), 0u);
  EXPECT_EQ(unconfirmed_starts(BootRecord{kBootRecordMagic, 5, 0}), 0u);
  EXPECT_EQ(unconfirmed_starts(make_boot_record(2)), 2u);
  BootRecord flipped = make_boot_record(1);
  flipped.unconfirmed_starts ^= 4;
  EXPECT_EQ(unconfirmed_starts(flipped), 0u);
}

TEST(BootRecovery, TheRecoveryPinAndTheHandOffWordKeepDfuMode) {
  BootInputs in;
  in.image = BootImageCheck::kOk;
  EXPECT_EQ(decide_boot(in).target, BootTarget::kApplication);
  in.boot_pin_held = true;
  EXPECT_EQ(decide_boot(in).target, BootTarget::kDfuMode);
  in.boot_pin_held = false;
  in.dfu_requested = true;
  EXPECT_EQ(decide_boot(in).target, BootTarget::kDfuMode);
  in.dfu_requested = false;
  in.image = BootImageCheck::kBadResetVector;
  EXPECT_EQ(decide_boot(in).target, BootTarget::kDfuMode);
}

TEST(BootRecovery, TheApplicationConfirmsOnlyAfterUsbStaysConfigured) {
  BootConfirmation c;
  const std::uint64_t ms = 1000;
  EXPECT_FALSE(c.poll(false, 0));
  EXPECT_FALSE(c.poll(false, 60'000 * ms));  // running without USB: not confirmed
  EXPECT_FALSE(c.poll(true, 60'000 * ms));
  EXPECT_FALSE(c.poll(true, 62'000 * ms));
  EXPECT_FALSE(c.poll(false, 62'500 * ms));  // the host dropped it: start again
  EXPECT_FALSE(c.poll(true, 63'000 * ms));
  EXPECT_FALSE(c.poll(true, 65'999 * ms));
  EXPECT_TRUE(c.poll(true, 66'000 * ms));
  EXPECT_TRUE(c.confirmed());
  EXPECT_FALSE(c.poll(true, 67'000 * ms));  // once
}

}  // namespace
}  // namespace flutterscan::firmware::test

namespace flutterscan::firmware::test {
namespace {

// Finding 6 end to end on the simulated board: an application that hangs
// before USB (watchdog resets, no host ever configures it) is started three
// times, then the bootloader stays in DFU mode, where a download brings a good
// image back.
TEST(BootRecoveryBoard, AHangingApplicationEndsInDfuModeAndCanBeReflashed) {
  sim::SimBoard board(sim::SimBoardConfig{}, good_image());
  EXPECT_EQ(board.mode(), sim::BoardMode::kApplication);
  EXPECT_EQ(board.unconfirmed_starts(), 1u);
  board.watchdog_reset();  // hung before USB
  EXPECT_EQ(board.mode(), sim::BoardMode::kApplication);
  board.watchdog_reset();
  EXPECT_EQ(board.mode(), sim::BoardMode::kApplication);
  EXPECT_EQ(board.unconfirmed_starts(), 3u);
  board.watchdog_reset();
  EXPECT_EQ(board.mode(), sim::BoardMode::kBootloader);
  enumerate_or_fail(board);
  const auto image = sim::make_application_image(kBoardIdStm32f405, 2, 0, 0, 6000, 5);
  EXPECT_EQ(dfu_download(board, image).final_status.state, DfuState::kDfuIdle);
  board.bus_reset();  // the deliberate leave clears the count
  EXPECT_EQ(board.mode(), sim::BoardMode::kApplication);
  EXPECT_EQ(board.unconfirmed_starts(), 1u);
}

TEST(BootRecoveryBoard, AnApplicationThatKeepsUsbConfiguredConfirmsItself) {
  sim::SimBoard board(sim::SimBoardConfig{}, good_image());
  enumerate_or_fail(board);
  board.port().run_for(2'000'000);
  board.poll();
  EXPECT_EQ(board.unconfirmed_starts(), 1u);  // 2 s: not yet
  board.port().run_for(1'000'000);
  board.poll();
  EXPECT_EQ(board.unconfirmed_starts(), 0u);  // 3 s configured: confirmed
  for (int i = 0; i < 5; ++i) {  // later watchdog resets of a working image: it keeps running
    board.watchdog_reset();
    EXPECT_EQ(board.mode(), sim::BoardMode::kApplication);
    enumerate_or_fail(board);
    board.port().run_for(3'000'000);
    board.poll();
  }
  EXPECT_EQ(board.unconfirmed_starts(), 0u);
}

TEST(BootRecoveryBoard, ThePowerOnResetAndTheRecoveryPin) {
  sim::SimBoard board(sim::SimBoardConfig{}, good_image());
  for (int i = 0; i < 3; ++i) board.watchdog_reset();
  EXPECT_EQ(board.mode(), sim::BoardMode::kBootloader);
  board.reset();  // power cycle: the SRAM record is gone, three new tries
  EXPECT_EQ(board.mode(), sim::BoardMode::kApplication);
  board.set_recovery_pin(true);
  board.reset();
  EXPECT_EQ(board.mode(), sim::BoardMode::kBootloader);
  board.set_recovery_pin(false);
  board.reset();
  EXPECT_EQ(board.mode(), sim::BoardMode::kApplication);
}

}  // namespace
}  // namespace flutterscan::firmware::test
