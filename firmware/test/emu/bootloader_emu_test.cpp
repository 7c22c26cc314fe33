// The real bootloader and application ELFs (build-fw-stm32f405) executed
// instruction by instruction in the Unicorn engine on the modelled chip
// (emu_chip.hpp; label emu, issue 15 item 4): from the reset vector through
// Reset_Handler's decision (boot_decision.hpp) to either the application's
// reset handler (VTOR, MSP and the jump of start_application) or
// bootloader_main (DFU mode); sector 0's write protection in the option bytes;
// and the application's start-up up to the USB driver's init.
// The strobe path: strobe_emu_test.cpp.
// Skipped (exit 77 via GTEST_SKIP) without the built ELF and image.

#include <gtest/gtest.h>
#include <unicorn/unicorn.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "emu_chip.hpp"
#include "emu_elf.hpp"
#include "flutterscan/common/crc32.hpp"
#include "flutterscan/common/image_header.hpp"
#include "flutterscan/firmware/boot_decision.hpp"

namespace flutterscan::firmware::emu {
namespace {

/// The BootRecord in no-init SRAM after the hand-off word (stm32f4_board.hpp).
constexpr std::uint32_t kBootRecordAt = 0x20000004;
constexpr std::uint32_t kRccCsr = kRccBase + 0x74;

BootRecord read_record(Chip& chip) {
  return {chip.read_word(kBootRecordAt), chip.read_word(kBootRecordAt + 4),
          chip.read_word(kBootRecordAt + 8), chip.read_word(kBootRecordAt + 12),
          chip.read_word(kBootRecordAt + 16)};
}

void write_record(Chip& chip, const BootRecord& r) {
  const std::uint32_t words[] = {r.magic, r.unconfirmed_starts, r.watchdog_resets, r.reset_flags,
                                 r.check};
  for (std::uint32_t i = 0; i < 5; ++i) chip.write_word(kBootRecordAt + 4 * i, words[i]);
}

class BootloaderEmu : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto elf = Elf::load(FLUTTERSCAN_BOOTLOADER_ELF);
    image_ = read_file(FLUTTERSCAN_FW_STM32F405_BIN);
    if (!elf || image_.empty())
      GTEST_SKIP() << "no bootloader ELF / application image (make fw-stm32f405 builds them)";
    bootloader_ = *elf;
    bootloader_main_ = bootloader_.symbol("_Z15bootloader_mainv");
    ASSERT_NE(bootloader_main_, 0u);
    app_reset_ = get<std::uint32_t>(image_, kAppVectorTableOffset + 4);
    app_sp_ = get<std::uint32_t>(image_, kAppVectorTableOffset);
  }

  /// A chip with the bootloader and `app` in flash, stopping at the
  /// application's reset handler or at bootloader_main.
  void flash(Chip& chip, const std::vector<std::uint8_t>& app) {
    for (const auto& s : bootloader_.segments) chip.write(s.address, s.bytes);
    if (!app.empty()) chip.write(kAppBase, app);
    chip.stop_at(app_reset_, "application");
    chip.stop_at(bootloader_main_, "dfu");
  }

  Elf bootloader_;
  std::vector<std::uint8_t> image_;
  std::uint32_t bootloader_main_ = 0;
  std::uint32_t app_reset_ = 0;
  std::uint32_t app_sp_ = 0;
};

TEST_F(BootloaderEmu, AGoodImageIsStartedThroughItsVectorTable) {
  Chip chip;
  flash(chip, image_);
  ASSERT_EQ(chip.run(), "application");
  EXPECT_EQ(chip.reg(UC_ARM_REG_PC) | 1u, app_reset_);
  EXPECT_EQ(chip.reg(UC_ARM_REG_MSP), app_sp_);
  EXPECT_EQ(chip.io(kScsBase + kScbVtor), kAppBase + kAppVectorTableOffset);
  // The recovery pin was read and everything put back as reset left it.
  EXPECT_EQ(chip.io(kRccBase + kRccAhb1Enr), 0x00100000u);
  EXPECT_EQ(chip.io(kGpioBBase + kGpioPupdr), 0x00000100u);
  // This start is on trial: one unconfirmed start in the record.
  const BootRecord record = read_record(chip);
  EXPECT_EQ(unconfirmed_starts(record), 1u);
  EXPECT_EQ(watchdog_resets(record), 0u);
  EXPECT_EQ(reset_flags(record), 0x0E000000u);  // a power-on's flags, handed over
  EXPECT_EQ(chip.read_word(0x20000000), 0u);    // the hand-off word
}

// Sector 0 (the bootloader) write-protected in the option bytes by the
// bootloader itself (RM0090 3.6.2): OPTKEYR unlock, OPTCR with only nWRP0
// cleared, OPTSTRT, BSY polled, OPTLOCK set again; on every later boot (the
// option bytes already protect it) nothing is written. On both paths (the
// application starts, or DFU mode).
TEST_F(BootloaderEmu, SectorZeroWriteProtectionIsSetOnceOnTheFirstBoot) {
  constexpr std::uint32_t kNwrp0 = 1u << 16;
  for (const bool with_image : {true, false}) {
    Chip chip;
    flash(chip, with_image ? image_ : std::vector<std::uint8_t>{});
    ASSERT_EQ(chip.run(), with_image ? "application" : "dfu");
    EXPECT_EQ(chip.option_programs(), 1);
    EXPECT_EQ(chip.io(kFlashOptcr), kFactoryOptcr & ~kNwrp0);  // the rest untouched, locked
    EXPECT_EQ(chip.writes_to(kFlashOptKeyr), (std::vector<std::uint32_t>{0x08192A3B, 0x4C5D6E7F}));
    const auto optcr = chip.writes_to(kFlashOptcr);
    ASSERT_EQ(optcr.size(), 3u);
    EXPECT_EQ(optcr[0], (kFactoryOptcr & ~kNwrp0) & ~1u);  // unlocked, nWRP0 cleared
    EXPECT_EQ(optcr[1], optcr[0] | 2u);                    // OPTSTRT
    EXPECT_EQ(optcr[2], optcr[0] | 1u);                    // OPTLOCK
  }
  // Already protected (and another sector too, and RDP as it is): left alone.
  const std::uint32_t protected_optcr = (kFactoryOptcr & ~kNwrp0 & ~(1u << 20));
  Chip chip;
  chip.set_option_bytes(protected_optcr);
  flash(chip, image_);
  ASSERT_EQ(chip.run(), "application");
  EXPECT_EQ(chip.option_programs(), 0);
  EXPECT_TRUE(chip.writes_to(kFlashOptKeyr).empty());
  EXPECT_TRUE(chip.writes_to(kFlashOptcr).empty());
  EXPECT_EQ(chip.io(kFlashOptcr), protected_optcr);
}

TEST_F(BootloaderEmu, EmptyOrCorruptImagesStayInDfuMode) {
  {
    Chip chip;
    flash(chip, {});
    EXPECT_EQ(chip.run(), "dfu");
  }
  auto corrupt = image_;
  corrupt[corrupt.size() / 2] ^= 0x01;
  Chip chip;
  flash(chip, corrupt);
  EXPECT_EQ(chip.run(), "dfu");
}

TEST_F(BootloaderEmu, AResetVectorOutsideTheImageStaysInDfuMode) {
  auto image = image_;
  const std::uint32_t into_bootloader = 0x08000101;
  std::memcpy(image.data() + kAppVectorTableOffset + 4, &into_bootloader, 4);
  ASSERT_TRUE(stamp_image(image));  // CRC-valid
  Chip chip;
  flash(chip, image);
  EXPECT_EQ(chip.run(), "dfu");
}

TEST_F(BootloaderEmu, TheHandOffWordTheRecoveryPinAndUnconfirmedStartsKeepDfuMode) {
  {
    Chip chip;
    flash(chip, image_);
    chip.write_word(0x20000000, 0xB007DF11);  // EnterBootloader / DFU_DETACH
    EXPECT_EQ(chip.run(), "dfu");
    EXPECT_EQ(chip.read_word(0x20000000), 0u);  // once
  }
  {
    Chip chip;
    flash(chip, image_);
    chip.recovery_pin_high = true;
    EXPECT_EQ(chip.run(), "dfu");
  }
  for (std::uint32_t starts : {2u, 3u}) {
    Chip chip;
    flash(chip, image_);
    write_record(chip, make_boot_record(starts));
    EXPECT_EQ(chip.run(), starts < kMaxUnconfirmedStarts ? "application" : "dfu") << starts;
  }
}

// The review of issue 15: the bootloader never read RCC_CSR, so an image that
// confirmed itself and then hung (watchdog resets) was started for ever. Now
// each reset's IWDGRSTF is counted in the record (confirmation keeps that
// count), the flags are cleared with RMVF and handed over in the record, and
// the third watchdog reset in a row stays in DFU mode. SRAM survives a
// watchdog reset: each chip starts with the record the one before left.
TEST_F(BootloaderEmu, ThreeWatchdogResetsInARowStayInDfuModeConfirmedOrNot) {
  constexpr std::uint32_t kIwdgRstf = 1u << 29;
  constexpr std::uint32_t kPinRstf = 1u << 26;  // NRST is driven by the watchdog reset too
  constexpr std::uint32_t kRmvf = 1u << 24;
  BootRecord record{};  // power-on
  std::vector<std::string> stops;
  for (std::uint32_t reset = 0; reset < 4; ++reset) {
    SCOPED_TRACE(reset);
    Chip chip;
    flash(chip, image_);
    if (reset > 0) {
      chip.set_reset_flags(kIwdgRstf | kPinRstf);
      write_record(chip, record);
    }
    stops.push_back(chip.run());
    record = read_record(chip);
    EXPECT_EQ(watchdog_resets(record), reset);
    EXPECT_EQ(reset_flags(record), reset > 0 ? kIwdgRstf | kPinRstf : 0x0E000000u);
    const auto csr = chip.writes_to(kRccCsr);
    EXPECT_TRUE(std::any_of(csr.begin(), csr.end(), [](std::uint32_t v) { return v & kRmvf; }));
    EXPECT_EQ(chip.io(kRccCsr) & 0xFE000000u, 0u);  // cleared: the next reset shows its own
    // The application confirms itself (a host command), then hangs.
    if (stops.back() == "application") record = confirm_boot_record(record);
  }
  EXPECT_EQ(stops, (std::vector<std::string>{"application", "application", "application", "dfu"}));
  // A reset that is not the watchdog's (the reset button) after two in a row: tried again.
  Chip chip;
  flash(chip, image_);
  chip.set_reset_flags(kPinRstf);
  write_record(chip, confirm_boot_record(make_boot_record(1, 2, kIwdgRstf | kPinRstf)));
  EXPECT_EQ(chip.run(), "application");
  EXPECT_EQ(watchdog_resets(read_record(chip)), 0u);
  EXPECT_EQ(unconfirmed_starts(read_record(chip)), 1u);
}

// Issue 46 defect 4: the bootloader never started the watchdog, and the
// application starts it only after its start-up, so an image whose reset
// handler loops (`b .`) passed the manifest check and never came back to DFU
// mode without the recovery jumper. The bootloader now starts the IWDG (2 s)
// just before the jump: three watchdog resets, then DFU mode, within 10 s.
TEST_F(BootloaderEmu, AnImageThatHangsAtItsFirstInstructionIsBackInDfuModeWithinTenSeconds) {
  auto image = image_;
  const std::uint32_t reset_offset = (app_reset_ & ~1u) - kAppBase;
  image[reset_offset] = Chip::kBranchToSelf & 0xFFu;  // b .
  image[reset_offset + 1] = Chip::kBranchToSelf >> 8;
  ASSERT_TRUE(stamp_image(image));  // CRC-valid: DFU's manifest check takes it
  const auto sleeps = bootloader_.wfi_in("_Z15bootloader_mainv");
  ASSERT_EQ(sleeps.size(), 1u);
  Chip chip;
  flash(chip, image);
  chip.sleep_at(sleeps[0]);
  ASSERT_EQ(chip.run(), "application");  // powered on: the first start
  constexpr std::uint64_t kTenSeconds = 10 * Chip::kCpuHz;
  ASSERT_EQ(chip.run_for(kTenSeconds - chip.cycles()), "ran");
  // Three watchdog resets in a row, about 2 s apart, then the bootloader keeps DFU mode.
  ASSERT_EQ(chip.watchdog_resets().size(), 3u);
  EXPECT_LT(chip.watchdog_resets().back(), 7 * Chip::kCpuHz);
  EXPECT_EQ(watchdog_resets(read_record(chip)), 3u);
  EXPECT_LT(chip.reg(UC_ARM_REG_PC), kAppBase) << "running the bootloader, not the image";
  EXPECT_TRUE(chip.otg_fs().attached()) << "DFU mode: the bootloader's USB device is up";
  EXPECT_EQ(chip.system_resets(), 0);
}

// Reset -> bootloader -> image check -> application: the application's own
// start-up (C runtime, clocks from HSE through the PLL, the port's GPIO,
// timers, DMA, NVIC, the controller loading its config from both flash copies,
// the watchdog, SysTick) runs on the modelled chip up to the USB driver's init.
TEST_F(BootloaderEmu, ResetRunsTheBootloaderThenTheApplicationsStartUpWithClocksUp) {
  const auto app = Elf::load(FLUTTERSCAN_FW_STM32F405_ELF);
  if (!app) GTEST_SKIP() << "no application ELF";
  const std::uint32_t usb_init =
      app->symbol("_ZN11flutterscan8firmware7stm32f411OtgFsDevice4initEm");
  ASSERT_NE(usb_init, 0u);
  Chip chip;
  flash(chip, image_);
  chip.stop_at(usb_init, "usb init");
  ASSERT_EQ(chip.run(), "application");
  ASSERT_EQ(chip.resume(), "usb init");
  // Clocks (RM0090 6.3): HSE on, PLL M 8, N 336, P 2, Q 7 from HSE, SYSCLK = PLL,
  // APB1 /4, APB2 /2, 5 wait states.
  EXPECT_NE(chip.io(kRccBase + 0x00) & (1u << 16), 0u);
  EXPECT_NE(chip.io(kRccBase + 0x00) & (1u << 24), 0u);
  const std::uint32_t pllcfgr = chip.io(kRccBase + 0x04);
  EXPECT_EQ(pllcfgr & 0x3Fu, 8u);
  EXPECT_EQ((pllcfgr >> 6) & 0x1FFu, 336u);
  EXPECT_EQ((pllcfgr >> 16) & 0x3u, 0u);  // P = 2
  EXPECT_EQ((pllcfgr >> 24) & 0xFu, 7u);
  EXPECT_NE(pllcfgr & (1u << 22), 0u);             // source HSE
  EXPECT_EQ(chip.io(kRccBase + 0x08) & 0x3u, 2u);  // SW = PLL
  EXPECT_EQ(chip.io(kFlashIfBase) & 0xFu, 5u);
  // LEDs: the board config's three, PC0..PC2, outputs driven low; no slot
  // table running or pre-armed.
  // The fourth channel (docs/hardware.md): PC3 (enable) and PC9 (set point) stay
  // inputs; PC6..PC8 alternate function (TIM3 CH1..CH3).
  const std::uint32_t moder = chip.io(kGpioCBase + kGpioModer);
  EXPECT_EQ(moder & 0xFFu, 0x15u);
  EXPECT_EQ((moder >> 12) & 0xFFu, 0x2Au);
  EXPECT_EQ(chip.io(kGpioCBase + 0x14) & 0x7u, 0u);
  const auto bsrr = chip.writes_to(kGpioCBase + 0x18);
  ASSERT_FALSE(bsrr.empty());
  EXPECT_EQ(bsrr.front() & 0xFFFFu, 0u);          // the first LED write sets nothing
  EXPECT_EQ(chip.io(kTim1Base + 0x00) & 1u, 0u);  // TIM1 stopped
  EXPECT_EQ(chip.io(kTim1Base + 0x08), 0u);       // no trigger: nothing pre-armed at boot
  // The watchdog started (IWDG_KR 0xCCCC), TIM2 (the clock) running.
  const auto kr = chip.writes_to(kIwdgBase + 0x00);
  EXPECT_NE(std::find(kr.begin(), kr.end(), 0xCCCCu), kr.end());
  EXPECT_EQ(chip.io(kTim2Base + 0x00) & 1u, 1u);
}

}  // namespace
}  // namespace flutterscan::firmware::emu
