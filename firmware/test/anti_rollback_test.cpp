// Anti-rollback: the security floor's thermometer code, and on a SimBoard an
// image that confirms itself raises the floor to its security_version, after
// which an older image is refused at DFU's manifest (errVENDOR) and not
// started by the bootloader, across power cycles (issue 46).
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "flutterscan/firmware/boot_decision.hpp"
#include "flutterscan/firmware/security_floor.hpp"
#include "flutterscan/firmware/sim/sim_board.hpp"
#include "flutterscan/firmware/sim/sim_security_floor.hpp"
#include "usb_test_host.hpp"

namespace flutterscan::firmware::test {
namespace {

std::vector<std::uint8_t> image_with_security(std::uint8_t security_version, std::uint32_t seed) {
  return sim::make_application_image(kBoardIdStm32f405, 2, security_version, 0, 6000, seed,
                                     kStm32f405AppRegion.load_address, security_version);
}

TEST(SecurityFloor, TheThermometerCodeOnlyEverClearsBits) {
  for (int v = 0; v < 256; ++v) {
    const auto cells = security_floor_cells(static_cast<std::uint8_t>(v));
    EXPECT_EQ(security_floor_of(cells), v);
    if (v > 0) {
      const auto lower = security_floor_cells(static_cast<std::uint8_t>(v - 1));
      for (std::size_t i = 0; i < cells.size(); ++i)
        EXPECT_EQ(cells[i] & lower[i], cells[i]) << v;  // raising programs 1 -> 0 only
    }
  }
  EXPECT_EQ(security_floor_cells(0), (std::array<std::uint8_t, kSecurityFloorBytes>{
                                         0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF,
                                         0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF,
                                         0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF,
                                         0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF}));
  EXPECT_EQ(security_floor_cells(10)[0], 0x00);
  EXPECT_EQ(security_floor_cells(10)[1], 0xFC);
  // A torn raise (some of the new bits programmed) reads between the two floors.
  auto torn = security_floor_cells(3);
  torn[0] &= 0xEF;  // bit 4 of the raise to 8, not bit 3
  EXPECT_EQ(security_floor_of(torn), 3);
  sim::SimSecurityFloor floor;
  EXPECT_TRUE(floor.raise(5));
  EXPECT_TRUE(floor.raise(2));  // never lowered
  EXPECT_EQ(floor.floor(), 5);
}

TEST(SecurityFloor, TheBootCheckRefusesAnImageBelowTheFloor) {
  const auto image = image_with_security(3, 1);
  EXPECT_EQ(check_boot_image(image, kStm32f405AppRegion, 0), BootImageCheck::kOk);
  EXPECT_EQ(check_boot_image(image, kStm32f405AppRegion, 3), BootImageCheck::kOk);
  EXPECT_EQ(check_boot_image(image, kStm32f405AppRegion, 4), BootImageCheck::kRolledBack);
}

TEST(AntiRollbackBoard, AConfirmedImageRaisesTheFloorAndAnOlderOneNeitherManifestsNorBoots) {
  sim::SimBoard board(sim::SimBoardConfig{}, image_with_security(2, 1));
  ASSERT_EQ(board.mode(), BoardMode::kApplication);
  EXPECT_EQ(board.security_floor().floor(), 0);  // not confirmed yet
  enumerate_or_fail(board);
  ASSERT_EQ(send_request(board, proto::Command::kGetInfo, 1), OutResult::kAck);
  ASSERT_TRUE(read_report(board).has_value());
  EXPECT_EQ(board.security_floor().floor(), 2);  // confirmed: the floor is its version
  // Into DFU mode; an older image (security version 1) is refused at the manifest.
  ASSERT_EQ(send_request(board, proto::Command::kEnterBootloader, 2,
                         proto::EnterBootloaderRequest{proto::kEnterBootloaderMagic}),
            OutResult::kAck);
  ASSERT_TRUE(read_report(board).has_value());
  ASSERT_EQ(board.mode(), BoardMode::kBootloader);
  enumerate_or_fail(board);
  const DownloadLog old = dfu_download(board, image_with_security(1, 2));
  EXPECT_EQ(old.final_status.state, DfuState::kError);
  EXPECT_EQ(old.final_status.status, DfuStatus::kErrVendor);
  // Its bytes are in flash now, but no power cycle starts them.
  board.reset();
  EXPECT_EQ(board.mode(), BoardMode::kBootloader);
  EXPECT_EQ(board.security_floor().floor(), 2);
  // The same or a newer version manifests and runs.
  enumerate_or_fail(board);
  const DownloadLog same = dfu_download(board, image_with_security(2, 3));
  EXPECT_EQ(same.final_status.state, DfuState::kDfuIdle);
  EXPECT_EQ(same.final_status.status, DfuStatus::kOk);
  board.bus_reset();
  EXPECT_EQ(board.mode(), BoardMode::kApplication);
}

}  // namespace
}  // namespace flutterscan::firmware::test
