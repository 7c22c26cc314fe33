// Host checks of the OTG_FS driver's arithmetic (otg_fs_layout.hpp) and
// register addresses against RM0090 chapter 34, and of the built bootloader
// image (when the fw-stm32f405 preset has built it).

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <vector>

#include "flutterscan/firmware/stm32f4/otg_fs_layout.hpp"
#include "flutterscan/firmware/stm32f4/registers.hpp"
#include "flutterscan/firmware/stm32f4/stm32f4_board.hpp"

namespace flutterscan::firmware::stm32f4 {
namespace {

namespace otg = reg::otg;

TEST(OtgFsLayout, FifoPlanFitsTheFifoRam) {
  using otg_layout::kFifoPlan;
  EXPECT_LE(kFifoPlan.total(), 320u);
  EXPECT_EQ(kFifoPlan.tx0_start(), 128u);
  EXPECT_EQ(kFifoPlan.tx1_start(), 160u);
  // Every TX FIFO holds at least one 64-byte packet.
  EXPECT_GE(kFifoPlan.tx0_words * 4, 64u);
  EXPECT_GE(kFifoPlan.tx1_words * 4, 64u);
  EXPECT_EQ(otg_layout::tx_fifo_value(128, 32), 0x00200080u);
}

TEST(OtgFsLayout, TurnaroundTimeFollowsTheAhbClock) {
  EXPECT_EQ(otg_layout::turnaround_time(168'000'000), 0x6u);
  EXPECT_EQ(otg_layout::turnaround_time(32'000'000), 0x6u);
  EXPECT_EQ(otg_layout::turnaround_time(30'000'000), 0x7u);
  EXPECT_EQ(otg_layout::turnaround_time(16'000'000), 0xDu);  // HSI alone
  EXPECT_EQ(otg_layout::turnaround_time(14'200'000), 0xFu);
}

TEST(OtgFsLayout, TransferSizeAndControlValues) {
  // DOEPTSIZ0: STUPCNT 3 (30:29), PKTCNT 1 (19), XFRSIZ 64.
  EXPECT_EQ(otg_layout::ep0_out_transfer_size(64), 0x60080040u);
  EXPECT_EQ(otg_layout::one_packet_transfer_size(64), 0x00080040u);
  EXPECT_EQ(otg_layout::one_packet_transfer_size(0), 0x00080000u);
  // Interrupt endpoint, 64 bytes, TX FIFO 1: MPSIZ, USBAEP, EPTYP 11, TXFNUM 1, SNAK, SD0PID.
  EXPECT_EQ(otg_layout::endpoint_control(usb::EndpointType::kInterrupt, 64, 1),
            64u | 1u << 15 | 3u << 18 | 1u << 22 | 1u << 27 | 1u << 28);
  EXPECT_EQ(otg_layout::fifo_words(0), 0u);
  EXPECT_EQ(otg_layout::fifo_words(1), 1u);
  EXPECT_EQ(otg_layout::fifo_words(64), 16u);
  EXPECT_EQ(otg_layout::fifo_words(65), 17u);
}

TEST(OtgFsLayout, ReceiveStatusDecoding) {
  // EP 1, 64 bytes, DATA1, OUT data packet received.
  const std::uint32_t word = 1u | 64u << 4 | 2u << 15 | 2u << 17;
  const auto s = otg_layout::decode_rx_status(word);
  EXPECT_EQ(s.endpoint, 1);
  EXPECT_EQ(s.bytes, 64u);
  EXPECT_EQ(s.packet_status, otg::kPktstsOutData);
  const auto setup = otg_layout::decode_rx_status(0u | 8u << 4 | 6u << 17);
  EXPECT_EQ(setup.bytes, 8u);
  EXPECT_EQ(setup.packet_status, otg::kPktstsSetupData);
}

TEST(OtgFsRegisters, AddressesFromRm0090) {
  EXPECT_EQ(otg::kGahbcfg, 0x50000008u);
  EXPECT_EQ(otg::kGrstctl, 0x50000010u);
  EXPECT_EQ(otg::kGrxstsp, 0x50000020u);
  EXPECT_EQ(otg::kGccfg, 0x50000038u);
  EXPECT_EQ(otg::dieptxf(1), 0x50000104u);
  EXPECT_EQ(otg::kDcfg, 0x50000800u);
  EXPECT_EQ(otg::kDaintmsk, 0x5000081Cu);
  EXPECT_EQ(otg::diepctl(0), 0x50000900u);
  EXPECT_EQ(otg::diepctl(1), 0x50000920u);
  EXPECT_EQ(otg::dtxfsts(1), 0x50000938u);
  EXPECT_EQ(otg::doepctl(1), 0x50000B20u);
  EXPECT_EQ(otg::doeptsiz(0), 0x50000B10u);
  EXPECT_EQ(otg::kPcgcctl, 0x50000E00u);
  EXPECT_EQ(otg::fifo(0), 0x50001000u);
  EXPECT_EQ(otg::fifo(1), 0x50002000u);
  EXPECT_EQ(reg::kUniqueIdAddress, 0x1FFF7A10u);
  EXPECT_EQ(reg::irq::kOtgFs, 67);
}

#ifdef FLUTTERSCAN_FW_BOOTLOADER_BIN
TEST(Stm32f4Bootloader, BuiltImageFitsSectorZeroAndBootsThere) {
  std::ifstream file(FLUTTERSCAN_FW_BOOTLOADER_BIN, std::ios::binary);
  if (!file)
    GTEST_SKIP() << "no bootloader image at " << FLUTTERSCAN_FW_BOOTLOADER_BIN
                 << " (make fw-stm32f405 builds it)";
  const std::vector<std::uint8_t> image((std::istreambuf_iterator<char>(file)),
                                        std::istreambuf_iterator<char>());
  ASSERT_GE(image.size(), 8u);
  EXPECT_LE(image.size(), kBootloaderSize);
  std::uint32_t sp = 0;
  std::uint32_t reset = 0;
  std::memcpy(&sp, image.data(), 4);
  std::memcpy(&reset, image.data() + 4, 4);
  EXPECT_EQ(sp, 0x20020000u);
  EXPECT_EQ(reset & 1u, 1u);  // Thumb
  EXPECT_GE(reset, kBootloaderBase);
  EXPECT_LT(reset, kBootloaderBase + image.size());
}
#endif

}  // namespace
}  // namespace flutterscan::firmware::stm32f4
