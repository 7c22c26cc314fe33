// The bootloader's DFU 1.1 mode through SimUsbController and SimFlash, driven
// the way dfu-util drives it: good download -> manifest -> application valid
// and started; aborted download; out-of-order block; corrupt image and wrong
// board (dfuERROR, stays in DFU mode, the next download works); upload; poll
// timeouts from the sector map; the bootloader's and the config sectors are
// never erased or written. Also the boot decision.

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "flutterscan/firmware/boot_decision.hpp"
#include "flutterscan/firmware/sim/sim_flash.hpp"
#include "flutterscan/firmware/sim/sim_security_floor.hpp"
#include "flutterscan/firmware/sim/sim_usb_controller.hpp"
#include "flutterscan/firmware/usb/bootloader_usb.hpp"
#include "usb_test_host.hpp"

namespace flutterscan::firmware::test {
namespace {

constexpr std::uint32_t kAppBase = kStm32f405AppRegion.load_address;

class DfuTest : public ::testing::Test {
 protected:
  DfuTest() : board_(sim::SimBoardConfig{}, factory_image()) {
    enumerate_or_fail(board_);
    detach_to_bootloader(board_);
  }

  ~DfuTest() override {
    // Whatever a test did: sector 0 (bootloader) and 1 (config page) untouched.
    for (int sector = 0; sector < 2; ++sector) {
      EXPECT_EQ(board_.flash().erase_count(sector), 0) << "sector " << sector;
      EXPECT_EQ(board_.flash().program_count(sector), 0) << "sector " << sector;
    }
    // Every control transfer since the last reset was answered as the seam requires.
    EXPECT_EQ(board_.usb().ep0_protocol_errors(), 0);
  }

  /// Downloads `image` in blocks of `transfer` bytes: it lands whole and contiguous in
  /// the application region and passes the manifest check.
  void download_whole(const std::vector<std::uint8_t>& image, std::size_t transfer) {
    const DownloadLog log = dfu_download(board_, image, transfer);
    ASSERT_FALSE(log.dnload_stalled);
    EXPECT_EQ(log.final_status.state, DfuState::kDfuIdle);
    EXPECT_EQ(log.final_status.status, DfuStatus::kOk);
    EXPECT_EQ(board_.bootloader()->dfu().downloaded_bytes(), image.size());
    EXPECT_EQ(region(image.size()), image);
    EXPECT_EQ(board_.bootloader()->dfu().last_manifest_check(), ImageCheck::kOk);
  }
  std::vector<std::uint8_t> region(std::size_t size) {
    const auto bytes = board_.flash().read(kAppBase, size);
    return {bytes.begin(), bytes.end()};
  }

  SimBoard board_;
};

TEST_F(DfuTest, GoodDownloadManifestsAndStartsTheApplicationAtTheNextReset) {
  // 40 KiB + 100 bytes: sectors 2, 3 and 4, a short last block.
  const auto image = sim::make_application_image(kBoardIdStm32f405, 3, 1, 0, 40 * 1024 + 100, 42);
  const DownloadLog log = dfu_download(board_, image);
  ASSERT_FALSE(log.dnload_stalled);
  ASSERT_FALSE(log.final_status.stalled);
  EXPECT_EQ(log.final_status.state, DfuState::kDfuIdle);
  EXPECT_EQ(log.final_status.status, DfuStatus::kOk);
  // Each block: dfuDNBUSY with a poll timeout, then dfuDNLOAD-IDLE; the first
  // block of each sector adds that sector's erase time.
  ASSERT_EQ(log.statuses.size(), 2 * 41 + 2u);
  for (std::size_t block = 0; block < 41; ++block) {
    const DfuStatusReply& busy = log.statuses[2 * block];
    EXPECT_EQ(busy.state, DfuState::kDnBusy) << block;
    const std::uint32_t erase = block == 0 || block == 16 ? 250 : block == 32 ? 550 : 0;
    EXPECT_EQ(busy.poll_timeout_ms, erase + 5) << block;
    EXPECT_EQ(log.statuses[2 * block + 1].state, DfuState::kDnloadIdle) << block;
  }
  EXPECT_EQ(log.statuses[82].state, DfuState::kManifest);
  EXPECT_EQ(log.statuses[82].poll_timeout_ms, usb::kDfuManifestPollMs);
  EXPECT_EQ(log.statuses[83].state, DfuState::kDfuIdle);
  EXPECT_EQ(region(image.size()), image);
  for (int sector = 2; sector <= 4; ++sector) EXPECT_EQ(board_.flash().erase_count(sector), 1);
  EXPECT_EQ(board_.flash().erase_count(5), 0);
  EXPECT_EQ(board_.bootloader()->dfu().last_manifest_check(), ImageCheck::kOk);

  // Still the bootloader until the host resets the bus (dfu-util -R), then the new application.
  EXPECT_EQ(board_.mode(), BoardMode::kBootloader);
  board_.bus_reset();
  ASSERT_EQ(board_.mode(), BoardMode::kApplication);
  enumerate_or_fail(board_);
  EXPECT_EQ(board_.bcd_device(), 0x0310);
  std::array<std::uint8_t, proto::kReportSize> report{};
  proto::encode_request(proto::Command::kGetInfo, 1, report);
  ASSERT_EQ(board_.interrupt_out(0x01, report), OutResult::kAck);
  const auto reply = read_report(board_);
  ASSERT_TRUE(reply.has_value());
  const auto info =
      proto::decode_payload<proto::InfoReply>(std::span<const std::uint8_t>(*reply).subspan(
          proto::kHeaderSize, proto::peek_header(*reply).payload_length));
  ASSERT_TRUE(info.ok());
  EXPECT_EQ(info.value().firmware_major, 3);
  EXPECT_EQ(info.value().build_id, read_image_header(image).image_crc32);
}

TEST_F(DfuTest, DetachAfterManifestAlsoStartsTheApplication) {
  const auto image = sim::make_application_image(kBoardIdStm32f405, 3, 2, 0, 5000, 3);
  ASSERT_EQ(dfu_download(board_, image).final_status.state, DfuState::kDfuIdle);
  EXPECT_FALSE(dfu_request(board_, DfuRequest::kDetach, 1000).stalled);
  EXPECT_EQ(board_.mode(), BoardMode::kApplication);
  EXPECT_EQ(board_.bcd_device(), 0x0320);
}

TEST_F(DfuTest, AbortedDownloadLeavesNoRunnableImageAndCanBeRepeated) {
  const auto image = sim::make_application_image(kBoardIdStm32f405, 3, 0, 0, 20 * 1024, 5);
  const auto half = std::span<const std::uint8_t>(image).first(10 * 1024);
  // Download half the blocks, as an interrupted dfu-util would, then ABORT.
  for (std::uint16_t block = 0; block < 10; ++block) {
    ASSERT_FALSE(
        dfu_request(board_, DfuRequest::kDnload, block, half.subspan(block * 1024u, 1024)).stalled);
    EXPECT_EQ(dfu_get_status(board_).state, DfuState::kDnBusy);
    EXPECT_EQ(dfu_get_status(board_).state, DfuState::kDnloadIdle);
  }
  EXPECT_FALSE(dfu_request(board_, DfuRequest::kAbort).stalled);
  EXPECT_EQ(dfu_get_status(board_).state, DfuState::kDfuIdle);
  // The header is in flash but the image is not: a reset stays in DFU mode.
  board_.reset();
  EXPECT_EQ(board_.mode(), BoardMode::kBootloader);
  enumerate_or_fail(board_);
  // A detach without a valid image is refused.
  EXPECT_TRUE(dfu_request(board_, DfuRequest::kDetach, 1000).stalled);
  EXPECT_EQ(dfu_get_status(board_).status, DfuStatus::kErrFirmware);
  EXPECT_FALSE(dfu_request(board_, DfuRequest::kClrStatus).stalled);
  // The whole download again.
  EXPECT_EQ(dfu_download(board_, image).final_status.state, DfuState::kDfuIdle);
  board_.bus_reset();
  EXPECT_EQ(board_.mode(), BoardMode::kApplication);
}

TEST_F(DfuTest, OutOfOrderBlockIsAnAddressError) {
  const auto image = sim::make_application_image(kBoardIdStm32f405, 3, 0, 0, 8 * 1024, 9);
  ASSERT_FALSE(dfu_request(board_, DfuRequest::kDnload, 0, std::span(image).first(1024)).stalled);
  EXPECT_EQ(dfu_get_status(board_).state, DfuState::kDnBusy);
  EXPECT_EQ(dfu_get_status(board_).state, DfuState::kDnloadIdle);
  // Block 2 instead of 1.
  ASSERT_FALSE(
      dfu_request(board_, DfuRequest::kDnload, 2, std::span(image).subspan(2048, 1024)).stalled);
  const DfuStatusReply s = dfu_get_status(board_);
  EXPECT_EQ(s.state, DfuState::kError);
  EXPECT_EQ(s.status, DfuStatus::kErrAddress);
  EXPECT_EQ(board_.flash().program_count(2), 1);  // block 2 was not written
  // dfu-util's recovery: CLRSTATUS, then the download from block 0.
  EXPECT_FALSE(dfu_request(board_, DfuRequest::kClrStatus).stalled);
  EXPECT_EQ(dfu_get_status(board_).state, DfuState::kDfuIdle);
  EXPECT_EQ(dfu_download(board_, image).final_status.state, DfuState::kDfuIdle);
}

TEST_F(DfuTest, DownloadStartingAtBlockOneIsRefused) {
  const auto image = sim::make_application_image(kBoardIdStm32f405, 3, 0, 0, 4 * 1024, 9);
  const DownloadLog log = dfu_download(board_, image, 1024, 1);
  EXPECT_EQ(log.final_status.state, DfuState::kError);
  EXPECT_EQ(log.final_status.status, DfuStatus::kErrAddress);
  EXPECT_EQ(board_.flash().program_count(2), 0);
}

TEST_F(DfuTest, ImagesPastTheRegionAreAddressErrors) {
  // 64 KiB + 1 block: block 64 lies past the application region.
  std::vector<std::uint8_t> image(65 * 1024, 0xA5);
  const DownloadLog log = dfu_download(board_, image);
  EXPECT_EQ(log.final_status.state, DfuState::kError);
  EXPECT_EQ(log.final_status.status, DfuStatus::kErrAddress);
  EXPECT_EQ(board_.flash().erase_count(5), 0);
}

struct BadImageCase {
  const char* name;
  std::vector<std::uint8_t> image;
  ImageCheck expected;
};

class DfuBadImageTest : public DfuTest, public ::testing::WithParamInterface<int> {};

std::vector<BadImageCase> bad_images() {
  std::vector<BadImageCase> cases;
  auto crc = sim::make_application_image(kBoardIdStm32f405, 4, 0, 0, 12'000, 11);
  crc[9000] ^= 0x40;
  cases.push_back({"bad CRC", crc, ImageCheck::kImageCrcMismatch});
  cases.push_back({"wrong board",
                   sim::make_application_image(kBoardIdQemuNetduinoplus2, 4, 0, 0, 12'000, 11),
                   ImageCheck::kWrongBoard});
  auto truncated = sim::make_application_image(kBoardIdStm32f405, 4, 0, 0, 12'000, 11);
  truncated.resize(11'000);
  cases.push_back({"truncated", truncated, ImageCheck::kTooShort});
  cases.push_back({"not an image", std::vector<std::uint8_t>(3000, 0x42), ImageCheck::kBadMagic});
  return cases;
}

TEST_P(DfuBadImageTest, GoesToDfuErrorStaysInDfuModeAndTheNextDownloadWorks) {
  const BadImageCase c = bad_images()[static_cast<std::size_t>(GetParam())];
  SCOPED_TRACE(c.name);
  const DownloadLog log = dfu_download(board_, c.image);
  ASSERT_FALSE(log.dnload_stalled);
  EXPECT_EQ(log.final_status.state, DfuState::kError);
  EXPECT_EQ(log.final_status.status, DfuStatus::kErrFirmware);
  EXPECT_EQ(board_.bootloader()->dfu().last_manifest_check(), c.expected);
  // Stays in DFU mode, through a bus reset and a chip reset.
  board_.bus_reset();
  EXPECT_EQ(board_.mode(), BoardMode::kBootloader);
  board_.reset();
  EXPECT_EQ(board_.mode(), BoardMode::kBootloader);
  enumerate_or_fail(board_);
  // Second download, good image.
  const auto good = sim::make_application_image(kBoardIdStm32f405, 4, 0, 1, 12'000, 12);
  if (dfu_get_status(board_).state == DfuState::kError) {
    ASSERT_FALSE(dfu_request(board_, DfuRequest::kClrStatus).stalled);
  }
  const DownloadLog second = dfu_download(board_, good);
  EXPECT_EQ(second.final_status.state, DfuState::kDfuIdle);
  EXPECT_EQ(second.final_status.status, DfuStatus::kOk);
  board_.bus_reset();
  EXPECT_EQ(board_.mode(), BoardMode::kApplication);
  EXPECT_EQ(board_.bcd_device(), 0x0401);
}

INSTANTIATE_TEST_SUITE_P(Images, DfuBadImageTest, ::testing::Range(0, 4));

TEST_F(DfuTest, ErrorStateNeedsClrStatus) {
  const auto image = sim::make_application_image(kBoardIdQemuNetduinoplus2, 4, 0, 0, 3000, 1);
  ASSERT_EQ(dfu_download(board_, image).final_status.state, DfuState::kError);
  // In dfuERROR only GETSTATUS, GETSTATE and CLRSTATUS are allowed.
  EXPECT_TRUE(dfu_request(board_, DfuRequest::kDnload, 0, std::span(image).first(64)).stalled);
  EXPECT_TRUE(dfu_request(board_, DfuRequest::kAbort).stalled);
  const ControlResult state =
      board_.control_transfer(0xA1, static_cast<std::uint8_t>(DfuRequest::kGetState), 0, 0, 1);
  EXPECT_EQ(state.data, (std::vector<std::uint8_t>{10}));
  EXPECT_FALSE(dfu_request(board_, DfuRequest::kClrStatus).stalled);
  EXPECT_EQ(dfu_get_status(board_).state, DfuState::kDfuIdle);
  EXPECT_EQ(dfu_get_status(board_).status, DfuStatus::kOk);
  EXPECT_TRUE(dfu_request(board_, DfuRequest::kClrStatus).stalled);  // not in dfuERROR
  EXPECT_EQ(dfu_get_status(board_).status, DfuStatus::kErrStalledPacket);
}

TEST_F(DfuTest, RequestsTheStateDoesNotAllowStall) {
  // Zero-length DNLOAD in dfuIDLE, block larger than wTransferSize, unknown request.
  EXPECT_TRUE(dfu_request(board_, DfuRequest::kDnload, 0).stalled);
  EXPECT_EQ(dfu_get_status(board_).status, DfuStatus::kErrStalledPacket);
  EXPECT_FALSE(dfu_request(board_, DfuRequest::kClrStatus).stalled);
  const std::vector<std::uint8_t> big(1025, 0);
  EXPECT_TRUE(dfu_request(board_, DfuRequest::kDnload, 0, big).stalled);
  EXPECT_FALSE(dfu_request(board_, DfuRequest::kClrStatus).stalled);
  EXPECT_TRUE(board_.control_transfer(0x21, 7, 0, 0, 0).stalled);
  EXPECT_EQ(dfu_get_status(board_).state, DfuState::kError);
  EXPECT_FALSE(dfu_request(board_, DfuRequest::kClrStatus).stalled);
  EXPECT_EQ(board_.flash().program_count(2), 0);
}

TEST_F(DfuTest, UploadReadsTheImageBackWithAShortLastBlock) {
  const auto image = sim::make_application_image(kBoardIdStm32f405, 3, 0, 0, 5 * 1024 + 300, 77);
  ASSERT_EQ(dfu_download(board_, image).final_status.state, DfuState::kDfuIdle);
  std::vector<std::uint8_t> read;
  for (std::uint16_t block = 0;; ++block) {
    const ControlResult r = board_.control_transfer(
        0xA1, static_cast<std::uint8_t>(DfuRequest::kUpload), block, 0, 1024);
    ASSERT_FALSE(r.stalled);
    read.insert(read.end(), r.data.begin(), r.data.end());
    if (r.data.size() < 1024) {
      EXPECT_EQ(block, 5);
      EXPECT_EQ(r.data.size(), 300u);
      break;
    }
    EXPECT_EQ(dfu_get_status(board_).state, DfuState::kUploadIdle);
  }
  EXPECT_EQ(read, image);
  EXPECT_EQ(dfu_get_status(board_).state, DfuState::kDfuIdle);
}

// Issue 15 finding 8: block n went to n x 1024 whatever the host's transfer
// size, so dfu-util -t 512 left gaps (and failed at the manifest).
TEST_F(DfuTest, SmallerTransferSizesGiveAContiguousImage) {
  for (const std::size_t transfer : {std::size_t{512}, std::size_t{256}, std::size_t{1000}}) {
    SCOPED_TRACE(transfer);
    const auto image = sim::make_application_image(kBoardIdStm32f405, 3, 0, 0, 9 * 1024 + 77,
                                                   static_cast<std::uint8_t>(transfer));
    ASSERT_NO_FATAL_FAILURE(download_whole(image, transfer));
    // Uploaded back in blocks of the same size.
    std::vector<std::uint8_t> read;
    for (std::uint16_t block = 0; block < 200; ++block) {
      const ControlResult r =
          board_.control_transfer(0xA1, static_cast<std::uint8_t>(DfuRequest::kUpload), block, 0,
                                  static_cast<std::uint16_t>(transfer));
      ASSERT_FALSE(r.stalled);
      read.insert(read.end(), r.data.begin(), r.data.end());
      if (r.data.size() < transfer) break;
    }
    EXPECT_EQ(read, image);
  }
}

// Issue 46 defect 6: with dfu-util -t 1022 the second block starts at an
// unaligned address, which the product's flash_program refuses (errPROG); the
// simulated flash now refuses it too. Every transfer size dfu-util allows
// (1 .. wTransferSize) gives the image, word-programmed.
TEST_F(DfuTest, TransferSizesThatAreNotAMultipleOfFourGiveTheImage) {
  for (const std::size_t transfer : {std::size_t{1022}, std::size_t{1023}, std::size_t{1021},
                                     std::size_t{6}, std::size_t{1}}) {
    SCOPED_TRACE(transfer);
    const auto image = sim::make_application_image(kBoardIdStm32f405, 3, 0, 0, 5 * 1024 + 77,
                                                   static_cast<std::uint8_t>(transfer));
    ASSERT_NO_FATAL_FAILURE(download_whole(image, transfer));
  }
}

TEST_F(DfuTest, UploadWithoutAnImageReadsTheWholeRegion) {
  board_.flash().bytes()[kAppBase - board_.flash().base()] ^= 0xFF;  // break the magic
  std::size_t total = 0;
  for (std::uint16_t block = 0; block < 100; ++block) {
    const ControlResult r = board_.control_transfer(
        0xA1, static_cast<std::uint8_t>(DfuRequest::kUpload), block, 0, 1024);
    ASSERT_FALSE(r.stalled);
    total += r.data.size();
    if (r.data.size() < 1024) break;
  }
  EXPECT_EQ(total, kStm32f405AppRegion.max_size);
}

TEST_F(DfuTest, AbortDuringUploadReturnsToIdle) {
  ASSERT_FALSE(
      board_.control_transfer(0xA1, static_cast<std::uint8_t>(DfuRequest::kUpload), 0, 0, 1024)
          .stalled);
  EXPECT_EQ(dfu_get_status(board_).state, DfuState::kUploadIdle);
  EXPECT_FALSE(dfu_request(board_, DfuRequest::kAbort).stalled);
  EXPECT_EQ(dfu_get_status(board_).state, DfuState::kDfuIdle);
}

TEST_F(DfuTest, FlashFailuresAreReported) {
  const auto image = sim::make_application_image(kBoardIdStm32f405, 3, 0, 0, 3000, 1);
  board_.flash().set_failures(true, false);
  DownloadLog log = dfu_download(board_, image);
  EXPECT_EQ(log.final_status.state, DfuState::kError);
  EXPECT_EQ(log.final_status.status, DfuStatus::kErrErase);
  EXPECT_FALSE(dfu_request(board_, DfuRequest::kClrStatus).stalled);
  board_.flash().set_failures(false, true);
  log = dfu_download(board_, image);
  EXPECT_EQ(log.final_status.status, DfuStatus::kErrProg);
  EXPECT_FALSE(dfu_request(board_, DfuRequest::kClrStatus).stalled);
  board_.flash().set_failures(false, false);
  EXPECT_EQ(dfu_download(board_, image).final_status.state, DfuState::kDfuIdle);
}

// The bootloader's main loop resets into the application only after the USB
// poll in which DFU mode decided to leave, and that poll may hold more
// requests: BootloaderUsb alone (no SimBoard, which resets at once) shows
// what they do. A DNLOAD then used to be accepted and its block written at the
// next GETSTATUS, so the chip reset to start an application that was no
// longer the one checked (the start-up check then stayed in DFU mode).
// Fuzz finding: firmware/fuzz/crashes/dfu-download-after-detach.
class DfuLeavingTest : public ::testing::Test {
 protected:
  DfuLeavingTest() {
    usb_.attach(&boot_);
    usb_.bus_reset();
    EXPECT_FALSE(usb_.control_transfer(0x00, 5, 1, 0, 0).stalled);  // SET_ADDRESS
    EXPECT_FALSE(usb_.control_transfer(0x00, 9, 1, 0, 0).stalled);  // SET_CONFIGURATION
  }

  ControlResult request(DfuRequest r, std::uint16_t value = 0,
                        std::span<const std::uint8_t> data = {}) {
    return usb_.control_transfer(usb::kDfuRequestOut, static_cast<std::uint8_t>(r), value, 0,
                                 static_cast<std::uint16_t>(data.size()), data);
  }
  DfuState get_status() {
    const ControlResult r =
        usb_.control_transfer(usb::kDfuRequestIn, static_cast<std::uint8_t>(DfuRequest::kGetStatus),
                              0, 0, usb::kDfuStatusSize);
    EXPECT_FALSE(r.stalled);
    return r.data.size() == usb::kDfuStatusSize ? static_cast<DfuState>(r.data[4])
                                                : DfuState::kAppIdle;
  }
  /// A DNLOAD of `block` with dfu-util's GETSTATUS polls after it; whether it was refused.
  bool dnload_refused(std::uint16_t block, std::span<const std::uint8_t> data) {
    if (request(DfuRequest::kDnload, block, data).stalled) return true;
    for (int i = 0; i < 3; ++i)
      if (get_status() == DfuState::kDnloadIdle) break;
    return false;
  }
  bool region_runs() {
    return choose_boot_target(false, flash_.read(kAppBase, kStm32f405AppRegion.max_size),
                              kStm32f405AppRegion) == BootTarget::kApplication;
  }
  void expect_nothing_written_after(const std::vector<std::uint8_t>& image) {
    std::array<int, 12> erases{}, programs{};
    for (int s = 0; s < 12; ++s) {
      erases[static_cast<std::size_t>(s)] = flash_.erase_count(s);
      programs[static_cast<std::size_t>(s)] = flash_.program_count(s);
    }
    const std::vector<std::uint8_t> garbage(usb::kDfuTransferSize, 0x5A);
    EXPECT_TRUE(dnload_refused(0, garbage));
    EXPECT_TRUE(dnload_refused(0, garbage));  // also from the dfuERROR that left
    EXPECT_FALSE(request(DfuRequest::kClrStatus).stalled);
    EXPECT_TRUE(dnload_refused(0, garbage));
    for (int s = 0; s < 12; ++s) {
      EXPECT_EQ(flash_.erase_count(s), erases[static_cast<std::size_t>(s)]) << "sector " << s;
      EXPECT_EQ(flash_.program_count(s), programs[static_cast<std::size_t>(s)]) << "sector " << s;
    }
    const auto bytes = flash_.read(kAppBase, image.size());
    EXPECT_TRUE(std::equal(image.begin(), image.end(), bytes.begin()));
    EXPECT_TRUE(region_runs());
    EXPECT_TRUE(boot_.leave_requested());
  }

  static constexpr std::array<std::uint8_t, 12> kUniqueId{1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12};
  static constexpr auto kDevice = usb::bootloader_device_descriptor(0x0100);
  sim::SimFlash flash_;
  sim::SimUsbController usb_;
  sim::SimSecurityFloor floor_;
  usb::BootloaderUsb boot_{usb_,    flash_,  floor_,   kStm32f405Flash, kStm32f405AppRegion,
                           kDevice, kUniqueId};
};

TEST_F(DfuLeavingTest, NoDownloadAfterDetach) {
  const auto image = sim::make_application_image(kBoardIdStm32f405, 3, 2, 0, 5000, 3);
  flash_.load(kAppBase, image);  // a valid application, as the factory programmed it
  ASSERT_FALSE(request(DfuRequest::kDetach, 1000).stalled);
  ASSERT_TRUE(boot_.leave_requested());
  expect_nothing_written_after(image);
}

TEST_F(DfuLeavingTest, NoDownloadAfterTheResetThatFollowsAManifest) {
  const auto image = sim::make_application_image(kBoardIdStm32f405, 3, 2, 0, 5000, 3);
  for (std::uint16_t block = 0; block * usb::kDfuTransferSize < image.size(); ++block) {
    const std::size_t at = block * usb::kDfuTransferSize;
    ASSERT_FALSE(dnload_refused(
        block, std::span<const std::uint8_t>(image).subspan(
                   at, std::min<std::size_t>(usb::kDfuTransferSize, image.size() - at))));
  }
  ASSERT_FALSE(request(DfuRequest::kDnload, 5).stalled);  // zero length: manifest
  ASSERT_EQ(get_status(), DfuState::kManifest);
  ASSERT_EQ(get_status(), DfuState::kDfuIdle);
  ASSERT_FALSE(boot_.leave_requested());
  usb_.bus_reset();
  ASSERT_TRUE(boot_.leave_requested());
  EXPECT_FALSE(usb_.control_transfer(0x00, 5, 1, 0, 0).stalled);
  EXPECT_FALSE(usb_.control_transfer(0x00, 9, 1, 0, 0).stalled);
  expect_nothing_written_after(image);
}

TEST(BootDecision, StartsOnlyAValidImageForThisBoardWhenNotAskedToStay) {
  std::vector<std::uint8_t> region(kStm32f405AppRegion.max_size, 0xFF);
  EXPECT_EQ(choose_boot_target(false, region, kStm32f405AppRegion), BootTarget::kDfuMode);
  const auto image = sim::make_application_image(kBoardIdStm32f405, 1, 0, 0, 9000, 2);
  std::copy(image.begin(), image.end(), region.begin());
  EXPECT_EQ(choose_boot_target(false, region, kStm32f405AppRegion), BootTarget::kApplication);
  EXPECT_EQ(choose_boot_target(true, region, kStm32f405AppRegion), BootTarget::kDfuMode);
  region[5000] ^= 1;
  EXPECT_EQ(choose_boot_target(false, region, kStm32f405AppRegion), BootTarget::kDfuMode);
  const auto other = sim::make_application_image(kBoardIdQemuNetduinoplus2, 1, 0, 0, 9000, 2);
  std::copy(other.begin(), other.end(), region.begin());
  EXPECT_EQ(choose_boot_target(false, region, kStm32f405AppRegion), BootTarget::kDfuMode);
}

TEST(SimBoardBoot, EmptyFlashBootsTheBootloader) {
  SimBoard board;
  EXPECT_EQ(board.mode(), BoardMode::kBootloader);
  const sim::Enumeration e = board.enumerate();
  ASSERT_TRUE(e.ok) << e.error;
  EXPECT_EQ(board.product_id(), proto::kUsbProductIdBootloader);
  EXPECT_TRUE(dfu_request(board, DfuRequest::kDetach, 1000).stalled);  // nothing to start
}

}  // namespace
}  // namespace flutterscan::firmware::test
