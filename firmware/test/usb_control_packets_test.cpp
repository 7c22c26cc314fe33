// Control transfers one endpoint-0 transaction at a time (SimUsbController's
// packet-level path, as the OTG_FS driver plays them) against the real USB
// device core, HID/DFU runtime and DFU mode: IN and OUT data stages in 64-byte
// packets, the status stage as what completes a transfer, a SETUP interrupting
// a data stage, SETUPs back to back. control_transfer() does each transfer in
// one step and could show none of this.
#include <gtest/gtest.h>

#include <array>
#include <vector>

#include "flutterscan/firmware/sim/sim_board.hpp"
#include "usb_test_host.hpp"

namespace flutterscan::firmware::test {
namespace {

using sim::Ep0Handshake;
using sim::Ep0Stage;
using sim::SimUsbController;

constexpr std::uint8_t kGetDescriptor = 6;
constexpr std::uint8_t kSetConfiguration = 9;
constexpr std::uint8_t kGetStatus = 0;

std::array<std::uint8_t, 8> setup(std::uint8_t type, std::uint8_t request, std::uint16_t value,
                                  std::uint16_t index, std::uint16_t length) {
  return usb::SetupPacket{type, request, value, index, length}.bytes();
}

/// An IN data stage read packet by packet until the device has no more.
struct InStage {
  std::vector<std::uint8_t> data;
  std::vector<std::size_t> packet_sizes;
};

InStage read_in_stage(SimUsbController& usb) {
  InStage stage;
  while (usb.ep0_stage() == Ep0Stage::kInData) {
    const sim::Ep0InPacket p = usb.ep0_in_packet();
    EXPECT_EQ(p.handshake, Ep0Handshake::kAck);
    if (p.handshake != Ep0Handshake::kAck) break;
    stage.packet_sizes.push_back(p.data.size());
    stage.data.insert(stage.data.end(), p.data.begin(), p.data.end());
  }
  return stage;
}

/// SETUP, the whole IN data stage, the OUT status packet.
std::vector<std::uint8_t> in_transfer(SimUsbController& usb, const std::array<std::uint8_t, 8>& s) {
  usb.setup_packet(s);
  EXPECT_EQ(usb.ep0_stage(), Ep0Stage::kInData);
  InStage stage = read_in_stage(usb);
  EXPECT_EQ(usb.ep0_out_packet({}), Ep0Handshake::kAck);
  EXPECT_EQ(usb.ep0_stage(), Ep0Stage::kIdle);
  return stage.data;
}

/// SETUP, the OUT data stage in 64-byte packets, the IN status packet.
Ep0Handshake out_transfer(SimUsbController& usb, const std::array<std::uint8_t, 8>& s,
                          std::span<const std::uint8_t> data) {
  usb.setup_packet(s);
  for (std::size_t at = 0; at < data.size(); at += usb::kEp0MaxPacket) {
    EXPECT_EQ(usb.ep0_stage(), Ep0Stage::kOutData) << at;
    const std::size_t n = std::min<std::size_t>(usb::kEp0MaxPacket, data.size() - at);
    EXPECT_EQ(usb.ep0_out_packet(data.subspan(at, n)), Ep0Handshake::kAck);
  }
  return usb.ep0_in_packet().handshake;
}

DfuState dfu_state_by_packets(SimUsbController& usb) {
  const auto bytes =
      in_transfer(usb, setup(usb::kDfuRequestIn, static_cast<std::uint8_t>(DfuRequest::kGetStatus),
                             0, 0, usb::kDfuStatusSize));
  EXPECT_EQ(bytes.size(), usb::kDfuStatusSize);
  return bytes.size() > 4 ? static_cast<DfuState>(bytes[4]) : DfuState::kError;
}

std::vector<std::uint8_t> flash_bytes(SimBoard& board, std::size_t n) {
  const auto bytes = board.flash().read(kStm32f405AppRegion.load_address, n);
  return {bytes.begin(), bytes.end()};
}

SimBoard& in_bootloader(SimBoard& board) {
  board.reset(true);  // the hand-off word: DFU mode
  EXPECT_EQ(board.mode(), BoardMode::kBootloader);
  enumerate_or_fail(board);
  return board;
}

TEST(UsbControlPackets, AnInDataStageComesIn64BytePacketsAndEqualsTheOneStepTransfer) {
  SimBoard board({}, sim::make_application_image(kBoardIdStm32f405, 1, 0, 0, 4096, 3));
  SimUsbController& usb = in_bootloader(board).usb();
  const auto upload = setup(usb::kDfuRequestIn, static_cast<std::uint8_t>(DfuRequest::kUpload), 0,
                            0, 1000);  // 15 packets of 64 and one of 40
  const auto abort =
      setup(usb::kDfuRequestOut, static_cast<std::uint8_t>(DfuRequest::kAbort), 0, 0, 0);
  const ControlResult reference = board.control_transfer(upload);
  ASSERT_FALSE(reference.stalled);
  ASSERT_EQ(reference.data.size(), 1000u);
  ASSERT_FALSE(board.control_transfer(abort).stalled);  // the next upload starts again at 0
  usb.setup_packet(upload);
  const InStage stage = read_in_stage(usb);
  EXPECT_EQ(stage.data, reference.data);
  ASSERT_EQ(stage.packet_sizes.size(), 16u);
  for (std::size_t i = 0; i < 15; ++i) EXPECT_EQ(stage.packet_sizes[i], usb::kEp0MaxPacket) << i;
  EXPECT_EQ(stage.packet_sizes.back(), 40u);  // the short packet ends it
  EXPECT_EQ(usb.ep0_stage(), Ep0Stage::kStatusOut);
  EXPECT_EQ(usb.ep0_in_packet().handshake, Ep0Handshake::kNak);  // nothing more
  const int completed = usb.ep0_transfers_completed();
  EXPECT_EQ(usb.ep0_out_packet({}), Ep0Handshake::kAck);  // the status stage
  EXPECT_EQ(usb.ep0_transfers_completed(), completed + 1);
  // wLength cuts a descriptor: 9 of the configuration's bytes, one packet.
  const ControlResult config = board.control_transfer(setup(0x80, kGetDescriptor, 0x0200, 0, 255));
  ASSERT_GT(config.data.size(), 9u);
  EXPECT_EQ(in_transfer(usb, setup(0x80, kGetDescriptor, 0x0200, 0, 9)),
            std::vector<std::uint8_t>(config.data.begin(), config.data.begin() + 9));
  EXPECT_EQ(usb.ep0_protocol_errors(), 0);
}

// A data stage shorter than wLength and a multiple of 64 bytes ends with a
// zero-length packet (USB 2.0 5.5.3): a DFU upload whose last block is 256 bytes.
TEST(UsbControlPackets, AShortInDataStageOfWholePacketsEndsWithAZeroLengthPacket) {
  SimBoard board({}, sim::make_application_image(kBoardIdStm32f405, 1, 0, 0, 4096, 3));
  SimUsbController& usb = in_bootloader(board).usb();
  constexpr std::uint16_t kBlock = 960;  // 15 packets; 4096 = 4 x 960 + 256
  std::vector<std::uint8_t> uploaded;
  std::vector<std::size_t> last_sizes;
  for (std::uint16_t block = 0; block < 5; ++block) {
    usb.setup_packet(setup(usb::kDfuRequestIn, static_cast<std::uint8_t>(DfuRequest::kUpload),
                           block, 0, kBlock));
    const InStage stage = read_in_stage(usb);
    ASSERT_EQ(usb.ep0_out_packet({}), Ep0Handshake::kAck);
    uploaded.insert(uploaded.end(), stage.data.begin(), stage.data.end());
    last_sizes = stage.packet_sizes;
  }
  EXPECT_EQ(uploaded, flash_bytes(board, 4096));
  EXPECT_EQ(last_sizes, (std::vector<std::size_t>{64, 64, 64, 64, 0}));
  EXPECT_EQ(usb.ep0_protocol_errors(), 0);
}

TEST(UsbControlPackets, ADfuDownloadIn64BytePacketsStartsTheImage) {
  SimBoard board({}, factory_image());
  SimUsbController& usb = in_bootloader(board).usb();
  const auto image = sim::make_application_image(kBoardIdStm32f405, 3, 0, 0, 6000, 11);
  std::uint16_t block = 0;
  for (std::size_t at = 0; at < image.size(); at += usb::kDfuTransferSize, ++block) {
    const std::size_t n = std::min<std::size_t>(usb::kDfuTransferSize, image.size() - at);
    const auto s = setup(usb::kDfuRequestOut, static_cast<std::uint8_t>(DfuRequest::kDnload), block,
                         0, static_cast<std::uint16_t>(n));
    // 1024 bytes: 16 full packets and no more; 6000 - 5 x 1024 = 880: 13 and a short one.
    ASSERT_EQ(out_transfer(usb, s, std::span<const std::uint8_t>(image).subspan(at, n)),
              Ep0Handshake::kAck)
        << block;
    for (int i = 0; i < 10 && dfu_state_by_packets(usb) != DfuState::kDnloadIdle; ++i) {
    }
    ASSERT_EQ(dfu_state_by_packets(usb), DfuState::kDnloadIdle) << block;
  }
  usb.setup_packet(
      setup(usb::kDfuRequestOut, static_cast<std::uint8_t>(DfuRequest::kDnload), block, 0, 0));
  EXPECT_EQ(usb.ep0_stage(), Ep0Stage::kStatusIn);  // no data stage
  ASSERT_EQ(usb.ep0_in_packet().handshake, Ep0Handshake::kAck);
  for (int i = 0; i < 10 && dfu_state_by_packets(usb) != DfuState::kDfuIdle; ++i) {
  }
  EXPECT_EQ(dfu_state_by_packets(usb), DfuState::kDfuIdle);
  EXPECT_EQ(flash_bytes(board, image.size()), image);
  EXPECT_EQ(usb.ep0_protocol_errors(), 0);
  board.bus_reset();  // manifest + reset: the new image runs
  EXPECT_EQ(board.mode(), BoardMode::kApplication);
  EXPECT_EQ(board.application()->device().configured(), false);
}

TEST(UsbControlPackets, ASetupInterruptingAnOutDataStageAbortsIt) {
  SimBoard board({}, factory_image());
  SimUsbController& usb = in_bootloader(board).usb();
  const auto image = sim::make_application_image(kBoardIdStm32f405, 3, 0, 0, 3000, 12);
  const int app_sector = 2;
  const int erases = board.flash().erase_count(app_sector);
  usb.setup_packet(setup(usb::kDfuRequestOut, static_cast<std::uint8_t>(DfuRequest::kDnload), 0, 0,
                         usb::kDfuTransferSize));
  for (std::size_t at = 0; at < 5 * usb::kEp0MaxPacket; at += usb::kEp0MaxPacket)
    ASSERT_EQ(usb.ep0_out_packet(std::span<const std::uint8_t>(image).subspan(at, 64)),
              Ep0Handshake::kAck);
  ASSERT_EQ(usb.ep0_stage(), Ep0Stage::kOutData);
  // The host gives up on it: a new SETUP. The block was never taken.
  EXPECT_EQ(dfu_state_by_packets(usb), DfuState::kDfuIdle);
  EXPECT_EQ(board.flash().erase_count(app_sector), erases);
  EXPECT_EQ(usb.ep0_out_packet(std::span<const std::uint8_t>(image).first(64)),
            Ep0Handshake::kNak);  // no data stage any more
  // A whole download afterwards goes through.
  const DownloadLog log = dfu_download(board, image);
  EXPECT_EQ(log.final_status.state, DfuState::kDfuIdle);
  EXPECT_EQ(flash_bytes(board, image.size()), image);
  EXPECT_EQ(usb.ep0_protocol_errors(), 0);
}

TEST(UsbControlPackets, ASetupInterruptingAnInDataStageIsAnsweredAfresh) {
  SimBoard board({}, sim::make_application_image(kBoardIdStm32f405, 1, 0, 0, 4096, 3));
  SimUsbController& usb = in_bootloader(board).usb();
  const ControlResult device = board.control_transfer(setup(0x80, kGetDescriptor, 0x0100, 0, 18));
  const int completed = usb.ep0_transfers_completed();
  usb.setup_packet(
      setup(usb::kDfuRequestIn, static_cast<std::uint8_t>(DfuRequest::kUpload), 0, 0, 1024));
  ASSERT_EQ(usb.ep0_in_packet().data.size(), usb::kEp0MaxPacket);  // one packet of 16
  EXPECT_EQ(in_transfer(usb, setup(0x80, kGetDescriptor, 0x0100, 0, 18)), device.data);
  EXPECT_EQ(usb.ep0_transfers_completed(), completed + 1);  // the interrupted one never did
  EXPECT_EQ(usb.ep0_protocol_errors(), 0);
}

// SETUPs back to back: the first transfer never reaches its status stage, so
// what the device does at the status stage (DFU_DETACH: reset into the
// bootloader) does not happen; the second is answered as if alone.
TEST(UsbControlPackets, BackToBackSetupsLeaveTheFirstUncompleted) {
  SimBoard board({}, factory_image());
  enumerate_or_fail(board);
  SimUsbController& usb = board.usb();
  const int entries = board.port().bootloader_entries();
  const auto detach = setup(usb::kDfuRequestOut, static_cast<std::uint8_t>(DfuRequest::kDetach),
                            1000, usb::kDfuRuntimeInterface, 0);
  usb.setup_packet(detach);
  EXPECT_EQ(usb.ep0_stage(), Ep0Stage::kStatusIn);
  const auto status = in_transfer(usb, setup(0x80, kGetStatus, 0, 0, 2));  // right behind it
  EXPECT_EQ(status.size(), 2u);
  board.poll();
  EXPECT_EQ(board.port().bootloader_entries(), entries);  // no detach
  // Two SETUPs, then one status stage: it is the second's.
  usb.setup_packet(setup(0x80, kGetDescriptor, 0x0100, 0, 18));
  usb.setup_packet(setup(0x00, kSetConfiguration, 1, 0, 0));
  EXPECT_EQ(usb.ep0_stage(), Ep0Stage::kStatusIn);
  EXPECT_EQ(usb.ep0_in_packet().handshake, Ep0Handshake::kAck);
  EXPECT_TRUE(board.application()->device().configured());
  EXPECT_EQ(usb.ep0_out_packet({}), Ep0Handshake::kNak);  // no stale status stage
  // The detach with its status stage does reset into the bootloader.
  usb.setup_packet(detach);
  EXPECT_EQ(usb.ep0_in_packet().handshake, Ep0Handshake::kAck);
  board.poll();
  EXPECT_EQ(board.port().bootloader_entries(), entries + 1);
  EXPECT_EQ(usb.ep0_protocol_errors(), 0);
}

TEST(UsbControlPackets, AStalledRequestStallsEveryPacketUntilTheNextSetup) {
  SimBoard board({}, factory_image());
  enumerate_or_fail(board);
  SimUsbController& usb = board.usb();
  usb.setup_packet(setup(0x80, kGetDescriptor, 0x7700, 0, 64));  // no such descriptor
  EXPECT_EQ(usb.ep0_stage(), Ep0Stage::kStalled);
  EXPECT_EQ(usb.ep0_in_packet().handshake, Ep0Handshake::kStall);
  EXPECT_EQ(usb.ep0_out_packet({}), Ep0Handshake::kStall);
  EXPECT_EQ(in_transfer(usb, setup(0x80, kGetDescriptor, 0x0100, 0, 18)).size(), 18u);
  // An OUT packet of more than 64 bytes is not a transaction: refused, nothing delivered.
  const std::vector<std::uint8_t> big(65, 0);
  EXPECT_EQ(usb.ep0_out_packet(big), Ep0Handshake::kStall);
  EXPECT_EQ(usb.ep0_protocol_errors(), 0);
}

}  // namespace
}  // namespace flutterscan::firmware::test
