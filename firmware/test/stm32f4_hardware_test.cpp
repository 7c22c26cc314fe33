// Host checks of the stm32f4 port's arithmetic and constants (no hardware):
// clock tree, flash wait states, slot-timer and PWM settings, watchdog, reset
// cause, DMA routing and register addresses, flash map, and the image header
// (including the header of the built fw-stm32f405 image, when it exists).

#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <vector>

#include "flutterscan/common/image_header.hpp"
#include "flutterscan/firmware/boot_decision.hpp"
#include "flutterscan/firmware/stm32f4/hardware_math.hpp"
#include "flutterscan/firmware/stm32f4/registers.hpp"
#include "flutterscan/firmware/stm32f4/stm32f4_board.hpp"

namespace flutterscan::firmware::stm32f4 {
namespace {

TEST(Stm32f4Clock, ProductPllGives168And48MHz) {
  EXPECT_TRUE(pll_valid(kPllFromHse));
  const ClockTree t = clock_tree(kPllFromHse);
  EXPECT_EQ(t.sysclk_hz, 168'000'000u);
  EXPECT_EQ(t.hclk_hz, 168'000'000u);
  EXPECT_EQ(t.pclk1_hz, 42'000'000u);
  EXPECT_EQ(t.pclk2_hz, 84'000'000u);
  EXPECT_EQ(t.usb_hz, 48'000'000u);
  EXPECT_EQ(t.tim_apb1_hz, 84'000'000u);  // APB1 divided: timers at 2 x pclk1
  EXPECT_EQ(t.tim_apb2_hz, 168'000'000u);
  EXPECT_EQ(flash_wait_states(t.hclk_hz), 5u);
}

TEST(Stm32f4Clock, HsiFallbackGivesTheSameTree) {
  EXPECT_TRUE(pll_valid(kPllFromHsi));
  const ClockTree a = clock_tree(kPllFromHse);
  const ClockTree b = clock_tree(kPllFromHsi);
  EXPECT_EQ(a.sysclk_hz, b.sysclk_hz);
  EXPECT_EQ(a.usb_hz, b.usb_hz);
}

TEST(Stm32f4Clock, PllRangesAreEnforced) {
  PllConfig pll = kPllFromHse;
  pll.p = 3;
  EXPECT_FALSE(pll_valid(pll));
  pll = kPllFromHse;
  pll.n = 400;  // 400 MHz VCO / 2 = 200 MHz SYSCLK: too fast
  EXPECT_FALSE(pll_valid(pll));
  pll = kPllFromHse;
  pll.m = 2;  // 4 MHz PLL input: outside 1..2 MHz
  EXPECT_FALSE(pll_valid(pll));
}

TEST(Stm32f4Clock, RegisterValues) {
  // PLLM 8, PLLN 336 (bit 6), PLLP /2 = 00, PLLSRC HSE (bit 22), PLLQ 7 (bit 24).
  EXPECT_EQ(pllcfgr_value(kPllFromHse, true), 8u | (336u << 6) | (1u << 22) | (7u << 24));
  EXPECT_EQ(pllcfgr_value(PllConfig{8'000'000, 8, 336, 4, 7}, false),
            8u | (336u << 6) | (1u << 16) | (7u << 24));
  // AHB /1, APB1 /4 = 101 at bit 10, APB2 /2 = 100 at bit 13.
  EXPECT_EQ(cfgr_prescaler_bits(BusPrescalers{}), (0b101u << 10) | (0b100u << 13));
  EXPECT_EQ(flash_wait_states(30'000'000), 0u);
  EXPECT_EQ(flash_wait_states(30'000'001), 1u);
  EXPECT_EQ(flash_wait_states(16'000'000), 0u);
}

TEST(Stm32f4Timers, EverySlotTimeIsExactAt168MHz) {
  for (std::uint32_t slot = kMinSlotTimeUs; slot <= kMaxSlotTimeUs; ++slot) {
    const SlotTimerSetting s = slot_timer_setting(slot, 168'000'000);
    ASSERT_TRUE(s.ok) << slot;
    EXPECT_LE(s.period.arr, 0xFFFFu);
    EXPECT_LE(s.period.psc, 0xFFFFu);
    EXPECT_EQ(slot_timer_period_ns(s.period, 168'000'000), slot * 1000ull) << slot;
  }
  // Finest resolution where it fits: no prescaler up to 390 us.
  EXPECT_EQ(slot_timer_setting(100, 168'000'000).period.psc, 0u);
  EXPECT_EQ(slot_timer_setting(100, 168'000'000).period.arr, 16'799u);
  EXPECT_EQ(slot_timer_setting(10'000, 168'000'000).period.psc, 27u);
  EXPECT_FALSE(slot_timer_setting(0, 168'000'000).ok);
}

TEST(Stm32f4Timers, SlotTimesAreExactOnTheHsiFallback) {
  for (std::uint32_t slot : {1u, 7u, 100u, 4096u, 10'000u}) {
    const SlotTimerSetting s = slot_timer_setting(slot, 16'000'000);
    ASSERT_TRUE(s.ok) << slot;
    EXPECT_EQ(slot_timer_period_ns(s.period, 16'000'000), slot * 1000ull);
  }
}

TEST(Stm32f4Timers, MicrosecondClockAndPwm) {
  EXPECT_EQ(microsecond_prescaler(84'000'000), 83u);
  const std::uint32_t arr = brightness_pwm_arr(84'000'000);
  EXPECT_EQ(arr, 4199u);  // 20 kHz
  EXPECT_EQ(brightness_compare(0, arr), 0u);
  EXPECT_EQ(brightness_compare(1000, arr), arr + 1);  // CCR > ARR: always high
  EXPECT_EQ(brightness_compare(500, arr), 2100u);
  EXPECT_EQ(brightness_compare(2000, arr), arr + 1);  // clamped
}

TEST(Stm32f4Watchdog, TimeoutAtNominalLsi) {
  const WatchdogSetting w = watchdog_setting(2000);
  ASSERT_TRUE(w.ok);
  EXPECT_LE(w.rlr, 4095u);
  EXPECT_GE(watchdog_timeout_ms(w), 2000u);
  EXPECT_LE(watchdog_timeout_ms(w), 2016u);
  EXPECT_FALSE(watchdog_setting(60'000).ok);  // beyond /256 x 4096 at 32 kHz
}

TEST(Stm32f4Reset, CauseFromCsr) {
  EXPECT_EQ(reset_cause_from_csr(1u << 29), ResetCause::kWatchdog);
  EXPECT_EQ(reset_cause_from_csr(1u << 30), ResetCause::kWatchdog);
  EXPECT_EQ(reset_cause_from_csr((1u << 29) | (1u << 26)), ResetCause::kWatchdog);
  EXPECT_EQ(reset_cause_from_csr((1u << 28) | (1u << 26)), ResetCause::kSoftware);
  EXPECT_EQ(reset_cause_from_csr((1u << 27) | (1u << 26) | (1u << 25)), ResetCause::kPowerOn);
  EXPECT_EQ(reset_cause_from_csr(1u << 26), ResetCause::kPowerOn);
}

TEST(Stm32f4Dma, Tim1UpIsDma2Stream5Channel6) {
  EXPECT_EQ(kTim1UpRoute.controller, 2);
  EXPECT_EQ(kTim1UpRoute.stream, 5);
  EXPECT_EQ(kTim1UpRoute.channel, 6);
  EXPECT_EQ(reg::dma::stream(reg::dma::kDma2, 5), 0x40026488u);
  EXPECT_EQ(reg::dma::status_register(5), reg::dma::kHisr);
  EXPECT_EQ(reg::dma::clear_register(5), reg::dma::kHifcr);
  EXPECT_EQ(reg::dma::flag_shift(5), 6);  // TCIF5 is HISR bit 11
  EXPECT_EQ(reg::dma::kFlagTc << reg::dma::flag_shift(5), 1u << 11);
  EXPECT_EQ(reg::dma::flag_shift(0), 0);
  EXPECT_EQ(reg::dma::flag_shift(2), 16);
  EXPECT_EQ(reg::dma::flag_shift(7), 22);
}

TEST(Stm32f4Registers, Addresses) {
  EXPECT_EQ(reg::gpio::port(kLedPort) + reg::gpio::kBsrr, 0x40020818u);  // GPIOC_BSRR
  EXPECT_EQ(reg::rcc::kCsr, 0x40023874u);
  EXPECT_EQ(reg::flash::kCr, 0x40023C10u);
  EXPECT_EQ(reg::tim::kTim1 + reg::tim::kArr, 0x4001002Cu);
  EXPECT_EQ(reg::tim::ccr(3), 0x3Cu);
  EXPECT_EQ(reg::nvic::word_for(reg::nvic::kIser0, reg::irq::kDma2Stream5), 0xE000E108u);
  EXPECT_EQ(reg::nvic::bit_for(reg::irq::kDma2Stream5), 1u << 4);
  EXPECT_EQ(reg::nvic::word_for(reg::nvic::kIser0, reg::irq::kTim2), 0xE000E100u);
}

TEST(Stm32f4FlashMap, SectorsAndRegions) {
  EXPECT_EQ(flash_sector_base(1), 0x08004000u);
  EXPECT_EQ(flash_sector_base(4), 0x08010000u);
  EXPECT_EQ(flash_sector_base(5), 0x08020000u);
  EXPECT_EQ(flash_sector_base(11), 0x080E0000u);
  EXPECT_EQ(flash_sector_of(kConfigBase), kConfigSector);
  EXPECT_EQ(flash_sector_size(kConfigSector), kConfigSize);
  EXPECT_EQ(flash_sector_of(kAppBase), kAppFirstSector);
  EXPECT_EQ(flash_sector_of(0x080FFFFF), 11);
  EXPECT_EQ(flash_sector_of(0x08100000), -1);
  // Bootloader, config page and application do not overlap.
  EXPECT_LE(kBootloaderBase + kBootloaderSize, kConfigBase);
  EXPECT_LE(kConfigBase + kConfigSize, kAppBase);
  EXPECT_EQ(kAppVectorOffset % 512, 0u);
}

std::vector<std::uint8_t> sample_image(std::size_t size) {
  std::vector<std::uint8_t> image(size, 0);
  ImageHeader h{};
  h.magic = kImageMagic;
  h.header_version = kImageHeaderVersion;
  h.header_size = sizeof(ImageHeader);
  h.board_id = kBoardId;
  h.version_major = 1;
  h.version_minor = 2;
  h.version_patch = 3;
  h.load_address = kAppBase;
  h.vector_table_offset = kAppVectorOffset;
  std::memcpy(image.data(), &h, sizeof h);
  for (std::size_t i = kAppVectorOffset; i < size; ++i) image[i] = static_cast<std::uint8_t>(i * 7);
  return image;
}

TEST(Stm32f4ImageHeader, StampedImagePassesAndCorruptionIsFound) {
  auto image = sample_image(4096);
  EXPECT_EQ(check_image(image, kBoardId, kAppMaxSize), ImageCheck::kBadHeader);  // not stamped
  ASSERT_TRUE(stamp_image(image));
  EXPECT_EQ(check_image(image, kBoardId, kAppMaxSize), ImageCheck::kOk);
  EXPECT_EQ(read_image_header(image).image_size, 4096u);
  EXPECT_EQ(read_image_header(image).image_crc32,
            crc32(std::span<const std::uint8_t>(image).subspan(kAppVectorOffset)));
  EXPECT_EQ(check_image(image, kBoardId + 1, kAppMaxSize), ImageCheck::kWrongBoard);
  EXPECT_EQ(check_image(image, kBoardId, 2048), ImageCheck::kBadLayout);
  EXPECT_EQ(check_image(std::span<const std::uint8_t>(image).first(4000), kBoardId, kAppMaxSize),
            ImageCheck::kTooShort);

  auto payload_flip = image;
  payload_flip[3000] ^= 0x10;
  EXPECT_EQ(check_image(payload_flip, kBoardId, kAppMaxSize), ImageCheck::kImageCrcMismatch);
  auto header_flip = image;
  header_flip[offsetof(ImageHeader, version_minor)] ^= 1;
  EXPECT_EQ(check_image(header_flip, kBoardId, kAppMaxSize), ImageCheck::kBadHeader);
  auto magic_flip = image;
  magic_flip[0] ^= 1;
  EXPECT_EQ(check_image(magic_flip, kBoardId, kAppMaxSize), ImageCheck::kBadMagic);
}

#ifdef FLUTTERSCAN_FW_STM32F405_BIN
TEST(Stm32f4ImageHeader, BuiltImageIsStampedCorrectly) {
  // The post-build step (stamp_image.cmake) computes the CRCs in CMake: check
  // them with the C++ code the bootloader will use.
  std::ifstream file(FLUTTERSCAN_FW_STM32F405_BIN, std::ios::binary);
  if (!file)
    GTEST_SKIP() << "no fw-stm32f405 image at " << FLUTTERSCAN_FW_STM32F405_BIN
                 << " (make fw-stm32f405 builds it)";
  const std::vector<std::uint8_t> image((std::istreambuf_iterator<char>(file)),
                                        std::istreambuf_iterator<char>());
  ASSERT_EQ(check_image(image, kBoardId, kAppMaxSize), ImageCheck::kOk);
  const ImageHeader h = read_image_header(image);
  EXPECT_EQ(h.image_size, image.size());
  EXPECT_EQ(h.load_address, kAppBase);
  EXPECT_EQ(h.vector_table_offset, kAppVectorOffset);
  // The vector table: initial SP at the top of SRAM, reset vector inside the image (Thumb).
  std::uint32_t sp = 0;
  std::uint32_t reset = 0;
  std::memcpy(&sp, image.data() + kAppVectorOffset, 4);
  std::memcpy(&reset, image.data() + kAppVectorOffset + 4, 4);
  EXPECT_EQ(sp, 0x20020000u);
  EXPECT_EQ(reset & 1u, 1u);
  EXPECT_GT(reset, kAppBase + kAppVectorOffset);
  EXPECT_LT(reset, kAppBase + h.image_size);
  // ... which is what the bootloader checks before it jumps.
  std::vector<std::uint8_t> region(kAppMaxSize, 0xFF);
  std::copy(image.begin(), image.end(), region.begin());
  EXPECT_EQ(check_boot_image(region, kStm32f405AppRegion), BootImageCheck::kOk);
}
#endif

static_assert(kAppVectorOffset == kAppVectorTableOffset,
              "the bootloader jumps through the offset the boot check requires");

}  // namespace
}  // namespace flutterscan::firmware::stm32f4
