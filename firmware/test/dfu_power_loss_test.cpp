// A DFU download with power lost at every flash operation (issue 15): after
// the power comes back the board always starts again, in DFU mode (the
// interrupted image is refused) or with a complete, checked image, never with
// sectors 0 or 1 touched, and the next download works.
#include <gtest/gtest.h>

#include <vector>

#include "flutterscan/firmware/boot_decision.hpp"
#include "flutterscan/firmware/sim/sim_flash.hpp"
#include "usb_test_host.hpp"

namespace flutterscan::firmware::test {
namespace {

constexpr std::uint32_t kAppBase = kStm32f405AppRegion.load_address;

TEST(DfuPowerLoss, EveryFlashOperationOfADownloadInterruptedRecovers) {
  // 20 KiB + 100 bytes: sectors 2 and 3, 21 blocks, a short last one.
  const auto image = sim::make_application_image(kBoardIdStm32f405, 3, 1, 0, 20 * 1024 + 100, 9);
  int operations = 0;
  {
    SimBoard board(sim::SimBoardConfig{}, factory_image());
    enumerate_or_fail(board);
    detach_to_bootloader(board);
    const int before = board.flash().operations();
    ASSERT_EQ(dfu_download(board, image).final_status.state, DfuState::kDfuIdle);
    operations = board.flash().operations() - before;
  }
  ASSERT_EQ(operations, 2 + 21);  // two sector erases, 21 blocks
  int cases = 0;
  int came_back_in_dfu = 0;
  for (int op = 0; op < operations; ++op) {
    for (const std::size_t bytes : {std::size_t{0}, std::size_t{1}, std::size_t{100},
                                    std::size_t{1023}, std::size_t{16 * 1024}}) {
      SCOPED_TRACE(testing::Message()
                   << "power lost in flash operation " << op << " after " << bytes << " bytes");
      SimBoard board(sim::SimBoardConfig{}, factory_image());
      enumerate_or_fail(board);
      detach_to_bootloader(board);
      board.flash().lose_power_at_operation(op, bytes);
      dfu_download(board, image);  // fails somewhere (the flash stops working)
      board.flash().restore_power();
      board.reset();  // power back
      const auto region = board.flash().read(kAppBase, kStm32f405AppRegion.max_size);
      if (board.mode() == BoardMode::kApplication) {
        // Only a complete image that passes the boot check ever starts.
        EXPECT_EQ(check_boot_image(region, kStm32f405AppRegion), BootImageCheck::kOk);
      } else {
        ++came_back_in_dfu;
      }
      // The device is reachable and a second download succeeds.
      enumerate_or_fail(board);
      if (board.mode() == BoardMode::kApplication) detach_to_bootloader(board);
      const DownloadLog again = dfu_download(board, image);
      EXPECT_EQ(again.final_status.state, DfuState::kDfuIdle);
      board.bus_reset();
      EXPECT_EQ(board.mode(), BoardMode::kApplication);
      enumerate_or_fail(board);
      EXPECT_EQ(board.bcd_device(), 0x0310);
      for (int sector = 0; sector < 2; ++sector) {
        EXPECT_EQ(board.flash().erase_count(sector), 0);
        EXPECT_EQ(board.flash().program_count(sector), 0);
      }
      ++cases;
    }
  }
  EXPECT_EQ(cases, operations * 5);
  EXPECT_GT(came_back_in_dfu, 0);
}

}  // namespace
}  // namespace flutterscan::firmware::test
