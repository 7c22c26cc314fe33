// The product images over the emulated USB bus (emu_usb_host.hpp; label emu,
// issue 15 item 4): from reset, the application enumerates and confirms itself
// when a host query is answered; EnterBootloader resets the chip into the
// bootloader's DFU mode, which enumerates with its own descriptors, and
// DFU_DETACH resets it into the application again. Every instruction is the
// real fw-stm32f405 images'; the resets are the chip's (AIRCR SYSRESETREQ).

#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "emu_chip.hpp"
#include "emu_product.hpp"
#include "emu_usb_host.hpp"
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
  UsbHost::Report request{}, reply{};
  proto::encode_request(proto::Command::kEnterBootloader, ++sequence_,
                        proto::EnterBootloaderRequest{proto::kEnterBootloaderMagic}, request);
  ASSERT_EQ(send(request, &reply), proto::Status::kOk);
  // The reply was read: the application resets into the bootloader, which
  // finds the hand-off word and keeps DFU mode.
  ASSERT_TRUE(runs_until_resets(1, 500));
  ASSERT_EQ(host_.run_for(kMs), "");
  EXPECT_FALSE(host_.configured());
  ASSERT_EQ(host_.enumerate(6), "");
  EXPECT_EQ(product_id(host_.device_descriptor()), proto::kUsbProductIdBootloader);
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

}  // namespace
}  // namespace flutterscan::firmware::emu
