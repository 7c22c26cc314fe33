// The product images over the emulated USB bus (emu_usb_host.hpp; label emu,
// issue 15 item 4): from reset, the application enumerates and confirms itself
// when a host query is answered; EnterBootloader resets the chip into the
// bootloader's DFU mode, which enumerates with its own descriptors, and
// DFU_DETACH resets it into the application again. Every instruction is the
// real fw-stm32f405 images'; the resets are the chip's (AIRCR SYSRESETREQ).

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <vector>

#include "emu_chip.hpp"
#include "emu_product.hpp"
#include "emu_usb_host.hpp"
#include "flutterscan/common/image_header.hpp"
#include "flutterscan/common/protocol.hpp"

namespace flutterscan::firmware::emu {
namespace {

namespace proto = flutterscan::protocol;

constexpr std::uint64_t kMs = Chip::kCyclesPerUs * 1000;
/// SRAM words of the hand-over (port/stm32f4 stm32f4_board.hpp): the
/// bootloader request word, then the BootRecord.
constexpr std::uint32_t kBootRecordAt = kSramBase + 4;

std::uint16_t product_id(const std::vector<std::uint8_t>& device_descriptor) {
  return static_cast<std::uint16_t>(device_descriptor.at(10) | device_descriptor.at(11) << 8);
}

class UsbEmu : public ::testing::Test {
 protected:
  void SetUp() override {
    if (const std::string missing = load_product(chip_); !missing.empty()) GTEST_SKIP() << missing;
    ASSERT_EQ(chip_.run(), "application");
    ASSERT_EQ(host_.enumerate(5), "");
  }

  proto::Status send(proto::Command command) {
    UsbHost::Report r{}, reply{};
    proto::encode_request(command, ++sequence_, r);
    return send(r, &reply);
  }
  proto::Status send(const UsbHost::Report& report, UsbHost::Report* reply) {
    const std::string error = host_.request(report, reply);
    EXPECT_EQ(error, "");
    return error.empty() ? static_cast<proto::Status>((*reply)[3])
                         : static_cast<proto::Status>(0xFF);
  }
  BootRecord boot_record() {
    BootRecord r{};
    std::array<std::uint32_t, sizeof r / 4> words{};
    for (std::size_t i = 0; i < words.size(); ++i)
      words[i] = chip_.read_word(kBootRecordAt + 4 * static_cast<std::uint32_t>(i));
    std::memcpy(&r, words.data(), sizeof r);
    return r;
  }
  /// Runs until the chip has reset itself `resets` times in all (at most
  /// `ms`); whether it has.
  bool runs_until_resets(int resets, int ms) {
    for (int i = 0; i < ms && chip_.system_resets() < resets; ++i)
      if (const std::string e = host_.run_for(kMs); !e.empty()) {
        ADD_FAILURE() << e;
        return false;
      }
    return chip_.system_resets() == resets;
  }

  /// EnterBootloader over USB; the bootloader enumerated at `address` in DFU mode.
  void enter_dfu_mode(std::uint8_t address) {
    UsbHost::Report request{}, reply{};
    proto::encode_request(proto::Command::kEnterBootloader, ++sequence_,
                          proto::EnterBootloaderRequest{proto::kEnterBootloaderMagic}, request);
    const int resets = chip_.system_resets();
    ASSERT_EQ(send(request, &reply), proto::Status::kOk);
    ASSERT_TRUE(runs_until_resets(resets + 1, 500));
    ASSERT_EQ(host_.enumerate(address), "");
    ASSERT_EQ(product_id(host_.device_descriptor()), proto::kUsbProductIdBootloader);
  }
  /// DFU_GETSTATUS until the state is `wanted`, waiting bwPollTimeout between
  /// them (DFU 1.1 6.1.2); "" or what went wrong.
  std::string dfu_wait_for(std::uint8_t wanted) {
    for (int i = 0; i < 200; ++i) {
      std::vector<std::uint8_t> status;
      if (std::string e = host_.control_in({0xA1, 3, 0, 0, 0, 0, 6, 0}, &status); !e.empty())
        return "DFU_GETSTATUS: " + e;
      if (status.size() != 6) return "DFU_GETSTATUS: " + std::to_string(status.size()) + " bytes";
      if (status[0] != 0) return "DFU_GETSTATUS: bStatus " + std::to_string(status[0]);
      if (status[4] == wanted) return "";
      const std::uint32_t poll_ms = status[1] | status[2] << 8 | status[3] << 16;
      if (std::string e = host_.run_for(std::max<std::uint32_t>(poll_ms, 1) * kMs); !e.empty())
        return e;
    }
    return "DFU state " + std::to_string(wanted) + " not reached";
  }
  /// A DFU 1.1 download: DNLOAD blocks of wTransferSize (1024), each until
  /// dfuDNLOAD-IDLE, then the zero-length DNLOAD and the manifest (until dfuIDLE).
  std::string dfu_download(const std::vector<std::uint8_t>& image) {
    std::uint16_t block = 0;
    for (std::size_t at = 0; at < image.size(); at += 1024, ++block) {
      const auto data = std::span<const std::uint8_t>(image).subspan(
          at, std::min<std::size_t>(1024, image.size() - at));
      const auto n = static_cast<std::uint16_t>(data.size());
      if (std::string e = host_.control_out(
              {0x21, 1, static_cast<std::uint8_t>(block), static_cast<std::uint8_t>(block >> 8), 0,
               0, static_cast<std::uint8_t>(n), static_cast<std::uint8_t>(n >> 8)},
              data);
          !e.empty())
        return "DNLOAD " + std::to_string(block) + ": " + e;
      if (std::string e = dfu_wait_for(5); !e.empty()) return e;  // dfuDNLOAD-IDLE
    }
    if (std::string e = host_.control_out({0x21, 1, static_cast<std::uint8_t>(block),
                                           static_cast<std::uint8_t>(block >> 8), 0, 0, 0, 0},
                                          {});
        !e.empty())
      return "final DNLOAD: " + e;
    return dfu_wait_for(2);  // dfuIDLE once manifested
  }

  Chip chip_;
  UsbHost host_{chip_};
  std::uint8_t sequence_ = 0;
};

TEST_F(UsbEmu, TheApplicationEnumeratesAndConfirmsItselfWhenAHostQueryIsAnswered) {
  const auto& d = host_.device_descriptor();
  EXPECT_EQ(d.at(8) | d.at(9) << 8, proto::kUsbVendorId);
  EXPECT_EQ(product_id(d), proto::kUsbProductIdApplication);
  // On trial: the bootloader counted one unconfirmed start; USB configured is not yet enough.
  EXPECT_EQ(unconfirmed_starts(boot_record()), 1u);
  ASSERT_EQ(host_.run_for(100 * kMs), "");
  EXPECT_EQ(unconfirmed_starts(boot_record()), 1u);
  ASSERT_EQ(send(proto::Command::kGetInfo), proto::Status::kOk);
  ASSERT_EQ(host_.run_for(2 * kMs), "");
  EXPECT_TRUE(boot_record_valid(boot_record()));
  EXPECT_EQ(unconfirmed_starts(boot_record()), 0u);
}

TEST_F(UsbEmu, EnterBootloaderResetsIntoDfuModeAndDfuDetachStartsTheApplicationAgain) {
  // The reply read, the application resets into the bootloader, which finds
  // the hand-off word and keeps DFU mode: PID 0x0002 on the bus.
  ASSERT_NO_FATAL_FAILURE(enter_dfu_mode(6));
  EXPECT_EQ(chip_.system_resets(), 1);
  std::vector<std::uint8_t> status;
  ASSERT_EQ(host_.control_in({0xA1, 3, 0, 0, 0, 0, 6, 0}, &status), "");  // DFU_GETSTATUS
  ASSERT_EQ(status.size(), 6u);
  EXPECT_EQ(status[0], 0u);                   // OK
  EXPECT_EQ(status[4], 2u);                   // dfuIDLE
  EXPECT_EQ(chip_.read_word(kSramBase), 0u);  // the hand-off word is used once
  // DFU_DETACH with the image in flash: the bootloader resets and starts it.
  ASSERT_EQ(host_.control_no_data({0x21, 0, 0xE8, 0x03, 0, 0, 0, 0}), "");
  ASSERT_TRUE(runs_until_resets(2, 500));
  ASSERT_EQ(host_.enumerate(7), "");
  EXPECT_EQ(product_id(host_.device_descriptor()), proto::kUsbProductIdApplication);
  EXPECT_EQ(unconfirmed_starts(boot_record()), 1u);  // a deliberate leave: new tries
  EXPECT_EQ(send(proto::Command::kGetStatus), proto::Status::kOk);
  EXPECT_EQ(chip_.system_resets(), 2);
}

// The whole update path on the real images: EnterBootloader, a DFU download
// of a new image (the product image with four bytes more, so another CRC) that
// the bootloader erases sectors for and programs word by word through the
// flash interface, the manifest, DFU_DETACH, and the new image running (its
// CRC is the build id GetInfo reports). Sector 0 is never erased.
TEST_F(UsbEmu, ADfuDownloadIsProgrammedThroughTheFlashInterfaceAndTheNewImageStarts) {
  std::vector<std::uint8_t> image = read_file(FLUTTERSCAN_FW_STM32F405_BIN);
  image.insert(image.end(), {0, 0, 0, 0});
  ASSERT_TRUE(stamp_image(image));
  const std::uint32_t new_crc = read_image_header(image).image_crc32;
  ASSERT_NO_FATAL_FAILURE(enter_dfu_mode(6));
  ASSERT_EQ(dfu_download(image), "");
  EXPECT_FALSE(chip_.flash_erases().empty());
  for (const int sector : chip_.flash_erases()) EXPECT_GE(sector, 2) << "the bootloader's sector";
  EXPECT_EQ(chip_.flash_programs(), static_cast<int>(image.size() / 4));
  for (std::size_t at = 0; at < image.size(); at += 4) {
    std::uint32_t word = 0;
    std::memcpy(&word, image.data() + at, 4);
    ASSERT_EQ(chip_.read_word(kAppBase + static_cast<std::uint32_t>(at)), word) << at;
  }
  ASSERT_EQ(host_.control_no_data({0x21, 0, 0xE8, 0x03, 0, 0, 0, 0}), "");  // DFU_DETACH
  ASSERT_TRUE(runs_until_resets(2, 500));
  ASSERT_EQ(host_.enumerate(7), "");
  EXPECT_EQ(product_id(host_.device_descriptor()), proto::kUsbProductIdApplication);
  UsbHost::Report request{}, reply{};
  proto::encode_request(proto::Command::kGetInfo, ++sequence_, request);
  ASSERT_EQ(send(request, &reply), proto::Status::kOk);
  proto::InfoReply info{};
  std::memcpy(&info, reply.data() + proto::kHeaderSize, sizeof info);
  EXPECT_EQ(info.build_id, new_crc);
}

// A download whose image fails its CRC (one byte flipped after stamping): the
// manifest reports an error, DFU_DETACH is refused (errFIRMWARE: no valid
// image to start) and a bus reset leaves the chip in DFU mode: the corrupt
// image never runs.
TEST_F(UsbEmu, ACorruptDownloadStaysInDfuMode) {
  std::vector<std::uint8_t> image = read_file(FLUTTERSCAN_FW_STM32F405_BIN);
  ASSERT_GT(image.size(), 1024u);
  image[image.size() - 1] ^= 0x01;
  ASSERT_NO_FATAL_FAILURE(enter_dfu_mode(6));
  const std::string manifest = dfu_download(image);
  EXPECT_NE(manifest.find("bStatus"), std::string::npos) << manifest;
  ASSERT_EQ(host_.control_no_data({0x21, 4, 0, 0, 0, 0, 0, 0}), "");  // DFU_CLRSTATUS
  ASSERT_EQ(dfu_wait_for(2), "");
  EXPECT_EQ(host_.control_no_data({0x21, 0, 0xE8, 0x03, 0, 0, 0, 0}),
            "status IN: STALL");  // DFU_DETACH
  std::vector<std::uint8_t> status;
  ASSERT_EQ(host_.control_in({0xA1, 3, 0, 0, 0, 0, 6, 0}, &status), "");
  ASSERT_EQ(status.size(), 6u);
  EXPECT_EQ(status[0], 0x0Au);  // errFIRMWARE
  ASSERT_EQ(host_.run_for(100 * kMs), "");
  ASSERT_EQ(host_.enumerate(7), "");  // a bus reset: no manifested image to leave for
  ASSERT_EQ(host_.run_for(100 * kMs), "");
  EXPECT_EQ(chip_.system_resets(), 1);
  EXPECT_EQ(product_id(host_.device_descriptor()), proto::kUsbProductIdBootloader);
}

}  // namespace
}  // namespace flutterscan::firmware::emu
