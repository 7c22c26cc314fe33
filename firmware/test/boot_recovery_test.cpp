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
  EXPECT_EQ(unconfirmed_starts(BootRecord{0, 0, 0, 0, 0}), 0u);
  EXPECT_EQ(unconfirmed_starts(BootRecord{kBootRecordMagic, 5, 0, 0, 0}), 0u);
  EXPECT_EQ(unconfirmed_starts(make_boot_record(2)), 2u);
  BootRecord flipped = make_boot_record(1);
  flipped.unconfirmed_starts ^= 4;
  EXPECT_EQ(unconfirmed_starts(flipped), 0u);
  // Every field is under the check word.
  for (int field = 0; field < 4; ++field) {
    BootRecord r = make_boot_record(1, 2, 0x24000000);
    ASSERT_EQ(watchdog_resets(r), 2u);
    ASSERT_EQ(reset_flags(r), 0x24000000u);
    std::uint32_t* words[] = {&r.magic, &r.unconfirmed_starts, &r.watchdog_resets, &r.reset_flags};
    *words[field] ^= 0x100;
    EXPECT_FALSE(boot_record_valid(r)) << field;
    EXPECT_EQ(watchdog_resets(r), 0u) << field;
    EXPECT_EQ(reset_flags(r), 0u) << field;
  }
}

// The review of issue 15: an image that confirms itself and then hangs
// (watchdog resets) looped forever, since confirmation cleared the only count
// and the bootloader never read RCC_CSR's IWDGRSTF.
TEST(BootRecovery, AnImageThatConfirmsThenHangsEndsInDfuModeAfterThreeWatchdogResets) {
  BootInputs in;
  in.image = BootImageCheck::kOk;
  BootRecord record{};  // power-on
  std::vector<BootTarget> targets;
  for (int reset = 0; reset < 6; ++reset) {
    in.watchdog_reset = reset > 0;  // the first boot is the power-on, every later one the watchdog
    in.unconfirmed_starts = unconfirmed_starts(record);
    in.watchdog_resets = watchdog_resets(record);
    const BootDecision d = decide_boot(in);
    targets.push_back(d.target);
    record = make_boot_record(d.unconfirmed_starts, d.watchdog_resets);
    // The application confirms itself (a host command), then hangs.
    if (d.target == BootTarget::kApplication) record = confirm_boot_record(record);
    EXPECT_EQ(unconfirmed_starts(record), 0u);
  }
  EXPECT_EQ(targets, (std::vector<BootTarget>{BootTarget::kApplication, BootTarget::kApplication,
                                              BootTarget::kApplication, BootTarget::kDfuMode,
                                              BootTarget::kDfuMode, BootTarget::kDfuMode}));
  EXPECT_EQ(watchdog_resets(record), kMaxWatchdogResets + 1);  // saturated, never wraps
}

TEST(BootRecovery, ConfirmationKeepsTheWatchdogCountAndAnyOtherResetClearsIt) {
  const BootRecord confirmed = confirm_boot_record(make_boot_record(2, 2, 0x24000000));
  EXPECT_EQ(unconfirmed_starts(confirmed), 0u);
  EXPECT_EQ(watchdog_resets(confirmed), 2u);
  EXPECT_EQ(reset_flags(confirmed), 0x24000000u);
  EXPECT_EQ(watchdog_resets(confirm_boot_record(BootRecord{})), 0u);  // power-on SRAM
  BootInputs in;
  in.image = BootImageCheck::kOk;
  in.watchdog_resets = 2;
  in.watchdog_reset = true;  // a third in a row
  EXPECT_EQ(decide_boot(in).target, BootTarget::kDfuMode);
  EXPECT_EQ(decide_boot(in).watchdog_resets, 3u);
  in.watchdog_reset = false;  // a pin or software reset in between: the count starts again
  const BootDecision d = decide_boot(in);
  EXPECT_EQ(d.target, BootTarget::kApplication);
  EXPECT_EQ(d.watchdog_resets, 0u);
  in.watchdog_resets = 1;  // a second watchdog reset in a row: still tried
  in.watchdog_reset = true;
  EXPECT_EQ(decide_boot(in).target, BootTarget::kApplication);
  EXPECT_EQ(decide_boot(in).watchdog_resets, 2u);
  in.watchdog_resets = 0xFFFFFFFF;  // a record's worst value: no wrap back to 0
  EXPECT_EQ(decide_boot(in).target, BootTarget::kDfuMode);
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
  EXPECT_FALSE(c.poll(false, 0, 0));
  EXPECT_FALSE(c.poll(false, 0, 60'000 * ms));  // running without USB: not confirmed
  EXPECT_FALSE(c.poll(true, 0, 60'000 * ms));
  EXPECT_FALSE(c.poll(true, 0, 62'000 * ms));
  EXPECT_FALSE(c.poll(false, 0, 62'500 * ms));  // the host dropped it: start again
  EXPECT_FALSE(c.poll(true, 0, 63'000 * ms));
  EXPECT_FALSE(c.poll(true, 0, 65'999 * ms));
  EXPECT_TRUE(c.poll(true, 0, 66'000 * ms));
  EXPECT_TRUE(c.confirmed());
  EXPECT_FALSE(c.poll(true, 0, 67'000 * ms));  // once
}

// Issue 15 asks that a host command (or a timeout) confirm the image; before
// the review only the 3 s timeout did. A GetInfo/GetStatus answered over
// configured USB now confirms at once.
TEST(BootRecovery, AHostQueryOverConfiguredUsbConfirmsAtOnce) {
  const std::uint64_t ms = 1000;
  BootConfirmation c;
  EXPECT_FALSE(c.poll(false, 1, 0));  // answered without configured USB: not a host's
  EXPECT_FALSE(c.poll(true, 1, 10 * ms));
  EXPECT_FALSE(c.poll(true, 1, 20 * ms));  // the same count: nothing new
  EXPECT_TRUE(c.poll(true, 2, 30 * ms));   // one more query over configured USB
  EXPECT_TRUE(c.confirmed());
  EXPECT_FALSE(c.poll(true, 3, 40 * ms));  // once
  BootConfirmation fresh;
  EXPECT_TRUE(fresh.poll(true, 1, 0));  // the first pass after it is configured
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
  board.reset();                              // a power cycle: confirmed again, running
  EXPECT_EQ(board.mode(), sim::BoardMode::kApplication);
  enumerate_or_fail(board);
  board.port().run_for(3'000'000);
  board.poll();
  EXPECT_EQ(board.unconfirmed_starts(), 0u);
}

// The review of issue 15: an image that confirms itself on every start and then
// hangs (watchdog resets) was started for ever (before the fix this board ran
// the application after each of five such resets). Now the third watchdog reset
// in a row keeps DFU mode, confirmation or not, and a download brings it back.
TEST(BootRecoveryBoard, AnImageThatConfirmsThenHangsEndsInDfuModeAfterThreeWatchdogResets) {
  sim::SimBoard board(sim::SimBoardConfig{}, good_image());
  std::vector<sim::BoardMode> modes;
  for (int i = 0; i < 4; ++i) {
    if (board.mode() == sim::BoardMode::kApplication) {
      enumerate_or_fail(board);
      board.port().run_for(3'000'000);
      board.poll();
      EXPECT_EQ(board.unconfirmed_starts(), 0u) << i;  // confirmed
    }
    board.watchdog_reset();  // then hung
    modes.push_back(board.mode());
    EXPECT_EQ(board.watchdog_resets(), static_cast<std::uint32_t>(i + 1)) << i;
  }
  EXPECT_EQ(modes, (std::vector<sim::BoardMode>{
                       sim::BoardMode::kApplication, sim::BoardMode::kApplication,
                       sim::BoardMode::kBootloader, sim::BoardMode::kBootloader}));
  enumerate_or_fail(board);
  const auto image = sim::make_application_image(kBoardIdStm32f405, 2, 0, 0, 6000, 5);
  EXPECT_EQ(dfu_download(board, image).final_status.state, DfuState::kDfuIdle);
  board.bus_reset();  // the deliberate leave clears both counts
  EXPECT_EQ(board.mode(), sim::BoardMode::kApplication);
  EXPECT_EQ(board.watchdog_resets(), 0u);
}

TEST(BootRecoveryBoard, AGetInfoOrGetStatusOverUsbConfirmsAtOnceOtherCommandsDoNot) {
  for (const auto query : {proto::Command::kGetInfo, proto::Command::kGetStatus}) {
    sim::SimBoard board(sim::SimBoardConfig{}, good_image());
    enumerate_or_fail(board);
    ASSERT_EQ(board.unconfirmed_starts(), 1u);
    ASSERT_EQ(send_request(board, proto::Command::kDisarm, 1), OutResult::kAck);
    ASSERT_TRUE(read_report(board).has_value());
    EXPECT_EQ(board.unconfirmed_starts(), 1u);  // not a query
    const std::uint64_t t = board.port().now_us();
    ASSERT_EQ(send_request(board, query, 2), OutResult::kAck);
    EXPECT_EQ(board.port().now_us(), t);  // no time passed: no timeout
    EXPECT_EQ(board.unconfirmed_starts(), 0u) << static_cast<int>(query);
    const auto reply = read_report(board);
    ASSERT_TRUE(reply.has_value());
    EXPECT_EQ((*reply)[0], static_cast<std::uint8_t>(query));
  }
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
