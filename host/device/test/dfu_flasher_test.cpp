// The DFU 1.1 request sequence against a scripted bootloader that follows the
// USB contract (blocks in order, manifest checks the header, errFIRMWARE).
#include "device/dfu_flasher.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <optional>

namespace flutterscan::device {
namespace {

using Bytes = std::vector<std::uint8_t>;
using std::chrono::milliseconds;

/// A DFU-mode bootloader for kStm32f405AppRegion, in memory.
class FakeBootloader final : public DfuControl {
 public:
  DfuState state = DfuState::kDfuIdle;
  std::uint8_t status = 0;
  Bytes flash;
  std::uint8_t security_floor = 0;  ///< as the firmware's security floor: errVENDOR below it
  std::size_t next_block = 0;
  int busy_polls_left = 0;
  std::optional<std::size_t> unplug_at_block;  ///< fails every transfer from that DNLOAD on
  bool unplugged = false;
  std::vector<DfuRequest> requests;

  Expected<Done> control_out(DfuRequest request, std::uint16_t value,
                             std::span<const std::uint8_t> data) override {
    requests.push_back(request);
    if (unplugged ||
        (request == DfuRequest::kDnload && unplug_at_block && value == *unplug_at_block)) {
      unplugged = true;
      return fail(ErrorKind::kGone, "no device");
    }
    switch (request) {
      case DfuRequest::kDnload:
        if (state != DfuState::kDfuIdle && state != DfuState::kDnloadIdle) return stall();
        if (data.empty()) {
          state = DfuState::kManifestSync;
          return done();
        }
        if (value != next_block || data.size() > protocol::kDfuTransferSize) {
          state = DfuState::kError;
          status = 0x08;  // errADDRESS
          return done();
        }
        if (flash.size() < value * protocol::kDfuTransferSize + data.size())
          flash.resize(value * protocol::kDfuTransferSize + data.size());
        std::memcpy(flash.data() + value * protocol::kDfuTransferSize, data.data(), data.size());
        ++next_block;
        state = DfuState::kDnloadSync;
        busy_polls_left = 1;
        return done();
      case DfuRequest::kClrStatus:
        if (state != DfuState::kError) return stall();
        state = DfuState::kDfuIdle;
        status = 0;
        return done();
      case DfuRequest::kAbort:
        state = DfuState::kDfuIdle;
        next_block = 0;
        return done();
      default:
        return stall();
    }
  }

  Expected<Bytes> control_in(DfuRequest request, std::uint16_t value,
                             std::uint16_t length) override {
    requests.push_back(request);
    if (unplugged) return fail<Bytes>(ErrorKind::kGone, "no device");
    if (request == DfuRequest::kGetStatus) {
      std::uint32_t poll_ms = 0;
      if (state == DfuState::kDnloadSync) {
        state = busy_polls_left-- > 0 ? DfuState::kDnBusy : DfuState::kDnloadIdle;
        poll_ms = 25;
      } else if (state == DfuState::kDnBusy) {
        state = DfuState::kDnloadIdle;
      } else if (state == DfuState::kManifestSync) {
        state = DfuState::kManifest;
        poll_ms = 40;
      } else if (state == DfuState::kManifest) {
        const bool valid = check_image(flash, kStm32f405AppRegion.board_id,
                                       kStm32f405AppRegion.max_size) == ImageCheck::kOk;
        const bool rolled_back = valid && read_image_header(flash).security_version < security_floor;
        state = valid && !rolled_back ? DfuState::kDfuIdle : DfuState::kError;
        status = !valid ? 0x0A : rolled_back ? 0x0B : 0;
        next_block = 0;
      }
      return Expected<Bytes>::success(Bytes{status, static_cast<std::uint8_t>(poll_ms),
                                            static_cast<std::uint8_t>(poll_ms >> 8), 0,
                                            static_cast<std::uint8_t>(state), 0});
    }
    if (request == DfuRequest::kUpload) {
      if (state != DfuState::kDfuIdle && state != DfuState::kUploadIdle)
        return fail<Bytes>(ErrorKind::kRejected, "stall");
      const std::size_t offset = std::size_t{value} * protocol::kDfuTransferSize;
      const std::size_t count =
          offset >= flash.size() ? 0 : std::min<std::size_t>(length, flash.size() - offset);
      state = count == length ? DfuState::kUploadIdle : DfuState::kDfuIdle;
      return Expected<Bytes>::success(
          Bytes(flash.begin() + static_cast<std::ptrdiff_t>(offset),
                flash.begin() + static_cast<std::ptrdiff_t>(offset + count)));
    }
    return fail<Bytes>(ErrorKind::kRejected, "stall");
  }

 private:
  static Expected<Done> stall() { return fail(ErrorKind::kRejected, "stall"); }
};

Bytes make_image(std::uint16_t board_id, std::size_t size) {
  Bytes image(size, 0);
  ImageHeader header{};
  header.magic = kImageMagic;
  header.header_version = kImageHeaderVersion;
  header.header_size = sizeof(ImageHeader);
  header.board_id = board_id;
  header.load_address = kStm32f405AppRegion.load_address;
  header.vector_table_offset = 512;
  std::memcpy(image.data(), &header, sizeof header);
  for (std::size_t i = 512; i < size; ++i) image[i] = static_cast<std::uint8_t>(i ^ (i >> 8));
  EXPECT_TRUE(stamp_image(image));
  return image;
}

struct SleepLog {
  milliseconds total{0};
  DfuSleeper sleeper() {
    return [this](milliseconds ms) { total += ms; };
  }
};

TEST(DfuDownload, WritesEveryBlockInOrderAndManifests) {
  FakeBootloader bootloader;
  const Bytes image = make_image(kStm32f405AppRegion.board_id, 5 * 1024 + 300);
  std::vector<std::pair<std::size_t, std::size_t>> progress;
  SleepLog sleeps;
  const auto result = dfu_download(
      bootloader, image,
      [&](std::size_t done, std::size_t total) { progress.emplace_back(done, total); },
      sleeps.sleeper());
  ASSERT_TRUE(result.ok()) << result.error().message;
  EXPECT_EQ(bootloader.flash, image);
  EXPECT_EQ(bootloader.state, DfuState::kDfuIdle);
  ASSERT_EQ(progress.size(), 7u);  // start + 6 blocks
  EXPECT_EQ(progress.front().first, 0u);
  EXPECT_EQ(progress.back().first, image.size());
  // bwPollTimeout honoured: 6 blocks x 25 ms busy + 40 ms manifest.
  EXPECT_EQ(sleeps.total, milliseconds(6 * 25 + 40));

  const auto readback = dfu_upload(bootloader, image.size());
  ASSERT_TRUE(readback.ok()) << readback.error().message;
  EXPECT_EQ(readback.value(), image);
}

TEST(DfuDownload, CorruptImageIsRefusedAtManifestWithErrFirmware) {
  FakeBootloader bootloader;
  Bytes image = make_image(kStm32f405AppRegion.board_id, 3000);
  image[2500] ^= 0xFF;
  SleepLog sleeps;
  const auto result = dfu_download(bootloader, image, nullptr, sleeps.sleeper());
  ASSERT_FALSE(result.ok());
  EXPECT_EQ(result.error().kind, ErrorKind::kRejected);
  EXPECT_NE(result.error().message.find("errFIRMWARE"), std::string::npos)
      << result.error().message;
  EXPECT_EQ(bootloader.state, DfuState::kError);
}

TEST(DfuDownload, AnImageBelowTheSecurityFloorIsBadInputNamedAntiRollback) {
  FakeBootloader bootloader;
  bootloader.security_floor = 2;
  const Bytes image = make_image(kStm32f405AppRegion.board_id, 3000);  // security version 0
  SleepLog sleeps;
  const auto result = dfu_download(bootloader, image, nullptr, sleeps.sleeper());
  ASSERT_FALSE(result.ok());
  EXPECT_EQ(result.error().kind, ErrorKind::kBadInput);  // the CLI exits 2
  EXPECT_NE(result.error().message.find("errVENDOR: the image's security version is below the "
                                        "newest confirmed image's on this controller "
                                        "(anti-rollback)"),
            std::string::npos)
      << result.error().message;
}

TEST(DfuDownload, InterruptedDownloadThenASecondOneSucceeds) {
  FakeBootloader bootloader;
  const Bytes image = make_image(kStm32f405AppRegion.board_id, 8 * 1024);
  bootloader.unplug_at_block = 3;
  SleepLog sleeps;
  const auto first = dfu_download(bootloader, image, nullptr, sleeps.sleeper());
  ASSERT_FALSE(first.ok());
  EXPECT_EQ(first.error().kind, ErrorKind::kGone);
  EXPECT_NE(first.error().message.find("DNLOAD block 3"), std::string::npos)
      << first.error().message;
  // Re-plugged: still the bootloader, left mid-download in dfuDNLOAD-IDLE.
  bootloader.unplugged = false;
  bootloader.unplug_at_block.reset();
  const auto second = dfu_download(bootloader, image, nullptr, sleeps.sleeper());
  ASSERT_TRUE(second.ok()) << second.error().message;
  EXPECT_EQ(bootloader.flash, image);
}

TEST(DfuDownload, LeavesDfuErrorWithClrStatusFirst) {
  FakeBootloader bootloader;
  bootloader.state = DfuState::kError;
  bootloader.status = 0x0A;
  const Bytes image = make_image(kStm32f405AppRegion.board_id, 2048);
  SleepLog sleeps;
  ASSERT_TRUE(dfu_download(bootloader, image, nullptr, sleeps.sleeper()).ok());
  ASSERT_FALSE(bootloader.requests.empty());
  EXPECT_EQ(bootloader.requests[1], DfuRequest::kClrStatus);
}

TEST(DfuStatusText, NamesTheContractsCodes) {
  EXPECT_EQ(dfu_status_text(0x0A).rfind("errFIRMWARE", 0), 0u);
  EXPECT_EQ(dfu_status_text(0x08).rfind("errADDRESS", 0), 0u);
  EXPECT_STREQ(dfu_state_name(DfuState::kDnBusy), "dfuDNBUSY");
}

}  // namespace
}  // namespace flutterscan::device
