// The USB device core through SimUsbController: enumeration as Linux does it
// with every descriptor checked byte by byte against the USB contract
// (docs/protocol.md), chapter 9 requests, STALL on bad requests and recovery,
// endpoint halt, bus reset.

#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <vector>

#include "flutterscan/firmware/usb/usb_descriptors.hpp"
#include "usb_test_host.hpp"

namespace flutterscan::firmware::test {
namespace {

using Bytes = std::vector<std::uint8_t>;

// The contract's descriptors, written out by hand (not from the builders).
const Bytes kAppDevice{0x12, 0x01, 0x00, 0x02, 0x00, 0x00, 0x00,
                       0x40, 0x09, 0x12, 0x01, 0x00, 0x34, 0x02,  // bcdDevice 2.3.4 -> 0x0234
                       0x01, 0x02, 0x03, 0x01};
const Bytes kAppConfiguration{
    0x09, 0x02, 0x3B, 0x00, 0x02, 0x01, 0x00, 0x80, 0x32,  // config 1, 2 interfaces, 100 mA
    0x09, 0x04, 0x00, 0x00, 0x02, 0x03, 0x00, 0x00, 0x00,  // interface 0: HID, 2 endpoints
    0x09, 0x21, 0x11, 0x01, 0x00, 0x01, 0x22, 0x19, 0x00,  // HID 1.11, report descriptor 25 B
    0x07, 0x05, 0x81, 0x03, 0x40, 0x00, 0x01,              // EP 0x81 interrupt 64 B, 1 ms
    0x07, 0x05, 0x01, 0x03, 0x40, 0x00, 0x01,              // EP 0x01 interrupt 64 B, 1 ms
    0x09, 0x04, 0x01, 0x00, 0x00, 0xFE, 0x01, 0x01, 0x04,  // interface 1: DFU runtime
    0x09, 0x21, 0x0F, 0xE8, 0x03, 0x00, 0x04, 0x10, 0x01,  // DFU: 0x0F, 1000 ms, 1024 B, 1.1
};
const Bytes kBootDevice{0x12, 0x01, 0x00, 0x02, 0x00, 0x00, 0x00,
                        0x40, 0x09, 0x12, 0x02, 0x00, 0x00, 0x01,  // bootloader 1.0.0
                        0x01, 0x02, 0x03, 0x01};
const Bytes kBootConfiguration{
    0x09, 0x02, 0x1B, 0x00, 0x01, 0x01, 0x00, 0x80, 0x32,  // config 1, 1 interface
    0x09, 0x04, 0x00, 0x00, 0x00, 0xFE, 0x01, 0x02, 0x04,  // interface 0: DFU mode
    0x09, 0x21, 0x0F, 0xE8, 0x03, 0x00, 0x04, 0x10, 0x01,
};
const Bytes kHidReport{0x06, 0x00, 0xFF, 0x09, 0x01, 0xA1, 0x01, 0x15, 0x00, 0x26, 0xFF, 0x00, 0x75,
                       0x08, 0x95, 0x40, 0x09, 0x02, 0x81, 0x02, 0x09, 0x03, 0x91, 0x02, 0xC0};
const char kSerial[] = "31002A000547333038373936";  // SimBoardConfig's default unique ID

class UsbDeviceTest : public ::testing::Test {
 protected:
  UsbDeviceTest() : image_(factory_image()), board_(sim::SimBoardConfig{}, image_) {}

  ControlResult get_descriptor(std::uint8_t type, std::uint8_t index, std::uint16_t length,
                               std::uint16_t w_index = 0, std::uint8_t request_type = 0x80) {
    return board_.control_transfer(request_type, 6, static_cast<std::uint16_t>(type << 8 | index),
                                   w_index, length);
  }
  ControlResult request(std::uint8_t type, std::uint8_t req, std::uint16_t value,
                        std::uint16_t index, std::uint16_t length) {
    return board_.control_transfer(type, req, value, index, length);
  }

  std::vector<std::uint8_t> image_;
  SimBoard board_;
};

TEST_F(UsbDeviceTest, LinuxEnumerationOfTheApplication) {
  ASSERT_EQ(board_.mode(), BoardMode::kApplication);
  const sim::Enumeration e = board_.enumerate(5);
  ASSERT_TRUE(e.ok) << e.error;
  EXPECT_EQ(e.device_descriptor, kAppDevice);
  EXPECT_EQ(e.configuration_descriptor, kAppConfiguration);
  EXPECT_EQ(e.hid_report_descriptor, kHidReport);
  EXPECT_EQ(e.manufacturer, "flutterscan");
  EXPECT_EQ(e.product, "flutterscan LED controller");
  EXPECT_EQ(e.serial, kSerial);
  EXPECT_EQ(board_.serial(), kSerial);
  EXPECT_EQ(board_.usb().address(), 5);
  EXPECT_EQ(board_.application()->device().state(), usb::DeviceState::kConfigured);
  EXPECT_EQ(board_.application()->hid().idle_rate(), 0);
  EXPECT_EQ(board_.usb().ep0_protocol_errors(), 0);
  // What the HIL harness puts into sysfs.
  Bytes sysfs = kAppDevice;
  sysfs.insert(sysfs.end(), kAppConfiguration.begin(), kAppConfiguration.end());
  EXPECT_EQ(board_.sysfs_descriptors(), sysfs);
  EXPECT_EQ(board_.vendor_id(), 0x1209);
  EXPECT_EQ(board_.product_id(), 0x0001);
}

TEST_F(UsbDeviceTest, LinuxEnumerationOfTheBootloaderGivesTheSameSerial) {
  enumerate_or_fail(board_);
  detach_to_bootloader(board_);
  const sim::Enumeration e = board_.enumerate();
  ASSERT_TRUE(e.ok) << e.error;
  EXPECT_EQ(e.device_descriptor, kBootDevice);
  EXPECT_EQ(e.configuration_descriptor, kBootConfiguration);
  EXPECT_TRUE(e.hid_report_descriptor.empty());
  EXPECT_EQ(e.product, "flutterscan DFU bootloader");
  EXPECT_EQ(e.serial, kSerial);
  EXPECT_EQ(board_.product_id(), 0x0002);
  // The DFU interface's name, as dfu-util shows it.
  const ControlResult name = get_descriptor(3, 4, 255, 0x0409);
  ASSERT_FALSE(name.stalled);
  const Bytes expected{36,  3, 'A', 0, 'p', 0, 'p', 0, 'l', 0, 'i', 0, 'c', 0, 'a', 0, 't', 0,
                       'i', 0, 'o', 0, 'n', 0, ' ', 0, 'f', 0, 'l', 0, 'a', 0, 's', 0, 'h', 0};
  EXPECT_EQ(name.data, expected);
}

TEST_F(UsbDeviceTest, DescriptorsAreCutToWLengthAndStringZeroListsEnUs) {
  EXPECT_EQ(get_descriptor(1, 0, 8).data, Bytes(kAppDevice.begin(), kAppDevice.begin() + 8));
  EXPECT_EQ(get_descriptor(2, 0, 9).data,
            Bytes(kAppConfiguration.begin(), kAppConfiguration.begin() + 9));
  EXPECT_EQ(get_descriptor(2, 0, 1000).data, kAppConfiguration);  // never more than there is
  EXPECT_EQ(get_descriptor(3, 0, 255).data, (Bytes{4, 3, 0x09, 0x04}));
  const ControlResult serial = get_descriptor(3, 3, 255, 0x0409);
  ASSERT_EQ(serial.data.size(), 50u);
  EXPECT_EQ(serial.data[0], 50);
  EXPECT_EQ(serial.data[2], '3');
  EXPECT_EQ(serial.data[3], 0);
  EXPECT_EQ(serial.data[48], '6');
}

TEST(SetupPacket, BytesAreTheWireOrderParseReadsBack) {
  constexpr usb::SetupPacket packet{0xA1, 0x03, 0x1234, 0x0001, 0x0006};
  constexpr std::array<std::uint8_t, 8> wire{0xA1, 0x03, 0x34, 0x12, 0x01, 0x00, 0x06, 0x00};
  EXPECT_EQ(packet.bytes(), wire);
  const usb::SetupPacket back = usb::SetupPacket::parse(wire);
  EXPECT_EQ(back.request_type, 0xA1);
  EXPECT_EQ(back.request, 0x03);
  EXPECT_EQ(back.value, 0x1234);
  EXPECT_EQ(back.index, 0x0001);
  EXPECT_EQ(back.length, 0x0006);
}

TEST(UsbSerial, UniqueIdBytesInAddressOrderAsUpperCaseHex) {
  const std::array<std::uint8_t, 12> uid{0x00, 0x01, 0xAB, 0xCD, 0xEF, 0x10,
                                         0x9F, 0xFF, 0x7E, 0x22, 0x5A, 0xA5};
  const auto serial = usb::serial_number(uid);
  EXPECT_EQ(std::string(serial.begin(), serial.end()), "0001ABCDEF109FFF7E225AA5");
}

TEST_F(UsbDeviceTest, StandardRequestsAfterEnumeration) {
  enumerate_or_fail(board_);
  EXPECT_EQ(request(0x80, 8, 0, 0, 1).data, (Bytes{1}));        // GET_CONFIGURATION
  EXPECT_EQ(request(0x80, 0, 0, 0, 2).data, (Bytes{0, 0}));     // GET_STATUS device
  EXPECT_EQ(request(0x81, 0, 0, 1, 2).data, (Bytes{0, 0}));     // GET_STATUS interface 1
  EXPECT_EQ(request(0x82, 0, 0, 0x81, 2).data, (Bytes{0, 0}));  // GET_STATUS EP 0x81
  EXPECT_EQ(request(0x81, 10, 0, 0, 1).data, (Bytes{0}));       // GET_INTERFACE 0
  EXPECT_FALSE(request(0x01, 11, 0, 0, 0).stalled);             // SET_INTERFACE 0 alt 0
  EXPECT_FALSE(request(0x02, 1, 0, 0x00, 0).stalled);           // CLEAR_FEATURE halt EP0
  EXPECT_FALSE(request(0x00, 9, 1, 0, 0).stalled);              // SET_CONFIGURATION again
  EXPECT_EQ(board_.usb().ep0_protocol_errors(), 0);
}

TEST_F(UsbDeviceTest, BadRequestsStallAndChangeNothing) {
  enumerate_or_fail(board_);
  struct Bad {
    const char* what;
    std::uint8_t type, req;
    std::uint16_t value, index, length;
  };
  const Bad bad[] = {
      {"GET_DESCRIPTOR device qualifier", 0x80, 6, 0x0600, 0, 10},
      {"GET_DESCRIPTOR string 9", 0x80, 6, 0x0309, 0x0409, 255},
      {"GET_DESCRIPTOR configuration 1", 0x80, 6, 0x0201, 0, 9},
      {"GET_DESCRIPTOR unknown type", 0x80, 6, 0x0F00, 0, 9},
      {"GET_DESCRIPTOR HID report of interface 1", 0x81, 6, 0x2200, 1, 25},
      {"SET_CONFIGURATION 2", 0x00, 9, 2, 0, 0},
      {"SET_ADDRESS while configured", 0x00, 5, 9, 0, 0},
      {"SET_ADDRESS 128", 0x00, 5, 128, 0, 0},
      {"SET_INTERFACE alt 1", 0x01, 11, 1, 0, 0},
      {"GET_INTERFACE of interface 2", 0x81, 10, 0, 2, 1},
      {"GET_STATUS of EP 0x82", 0x82, 0, 0, 0x82, 2},
      {"SET_FEATURE remote wakeup", 0x00, 3, 1, 0, 0},
      {"SET_FEATURE test mode", 0x00, 3, 2, 0x0100, 0},
      {"SET_FEATURE halt on EP0", 0x02, 3, 0, 0x00, 0},
      {"SET_FEATURE halt on EP 0x05", 0x02, 3, 0, 0x05, 0},
      {"SET_DESCRIPTOR", 0x00, 7, 0x0100, 0, 18},
      {"SYNCH_FRAME", 0x82, 12, 0, 0x81, 2},
      {"unknown standard request 2", 0x80, 2, 0, 0, 2},
      {"vendor request", 0xC0, 1, 0, 0, 8},
      {"class request to interface 5", 0xA1, 1, 0, 5, 64},
      {"class request to an endpoint", 0x22, 1, 0, 0x81, 0},
      {"HID GET_REPORT", 0xA1, 0x01, 0x0100, 0, 64},
      {"HID SET_PROTOCOL", 0x21, 0x0B, 0, 0, 0},
      {"HID SET_IDLE with report id", 0x21, 0x0A, 0x0001, 0, 0},
      {"DFU DNLOAD in runtime", 0x21, 1, 0, 1, 16},
      {"GET_CONFIGURATION with wLength 0", 0x80, 8, 0, 0, 0},
  };
  for (const Bad& b : bad) {
    const ControlResult r = request(b.type, b.req, b.value, b.index, b.length);
    EXPECT_TRUE(r.stalled) << b.what;
    // Recovery: the next good request works, and nothing changed.
    EXPECT_EQ(request(0x80, 8, 0, 0, 1).data, (Bytes{1})) << "after " << b.what;
    EXPECT_EQ(board_.usb().address(), 2) << b.what;
    EXPECT_FALSE(board_.endpoint_halted(0x81)) << b.what;
    EXPECT_FALSE(board_.endpoint_halted(0x01)) << b.what;
  }
  EXPECT_EQ(board_.mode(), BoardMode::kApplication);
  EXPECT_EQ(board_.usb().ep0_protocol_errors(), 0);
}

TEST_F(UsbDeviceTest, RequestsBeforeConfigurationAreLimited) {
  board_.bus_reset();
  EXPECT_TRUE(request(0x80, 0, 0, 0, 2).stalled);  // GET_STATUS in the default state
  EXPECT_TRUE(request(0x00, 9, 1, 0, 0).stalled);  // SET_CONFIGURATION without an address
  EXPECT_FALSE(request(0x00, 5, 3, 0, 0).stalled);
  EXPECT_TRUE(request(0x81, 10, 0, 0, 1).stalled);  // GET_INTERFACE: not configured
  EXPECT_TRUE(get_descriptor(0x22, 0, 25, 0, 0x81).stalled);
  EXPECT_EQ(request(0x80, 8, 0, 0, 1).data, (Bytes{0}));  // configuration 0
  EXPECT_FALSE(board_.usb().endpoint_open(0x81));
  EXPECT_FALSE(request(0x00, 9, 1, 0, 0).stalled);
  EXPECT_TRUE(board_.usb().endpoint_open(0x81));
  EXPECT_TRUE(board_.usb().endpoint_open(0x01));
  EXPECT_FALSE(request(0x00, 9, 0, 0, 0).stalled);  // back to the address state
  EXPECT_FALSE(board_.usb().endpoint_open(0x81));
}

TEST_F(UsbDeviceTest, EndpointHaltStallsTrafficUntilCleared) {
  enumerate_or_fail(board_);
  EXPECT_FALSE(request(0x02, 3, 0, 0x01, 0).stalled);  // SET_FEATURE(halt) OUT
  EXPECT_EQ(request(0x82, 0, 0, 0x01, 2).data, (Bytes{1, 0}));
  EXPECT_EQ(send_request(board_, proto::Command::kGetInfo, 1), OutResult::kStall);
  EXPECT_FALSE(request(0x02, 1, 0, 0x01, 0).stalled);  // CLEAR_FEATURE(halt)
  EXPECT_EQ(request(0x82, 0, 0, 0x01, 2).data, (Bytes{0, 0}));
  EXPECT_EQ(send_request(board_, proto::Command::kGetInfo, 2), OutResult::kAck);

  // Halting IN while the reply waits on it: the reply is not lost.
  EXPECT_TRUE(board_.usb().in_packet_waiting(0x81));
  EXPECT_FALSE(request(0x02, 3, 0, 0x81, 0).stalled);
  EXPECT_TRUE(board_.endpoint_halted(0x81));
  EXPECT_FALSE(read_report(board_).has_value());
  EXPECT_FALSE(request(0x02, 1, 0, 0x81, 0).stalled);
  const auto reply = read_report(board_);
  ASSERT_TRUE(reply.has_value());
  EXPECT_EQ(proto::peek_header(*reply).sequence, 2);
  EXPECT_EQ(proto::peek_header(*reply).status, static_cast<std::uint8_t>(proto::Status::kOk));
}

// Found by the fuzz target: CLEAR_FEATURE(HALT) on an IN endpoint that was not
// halted dropped the queued reply in the controller while the HID interface
// still waited for it to be taken, and SET_INTERFACE left OUT un-armed.
TEST_F(UsbDeviceTest, UnhaltingAnEndpointThatWasNotHaltedLosesNothing) {
  enumerate_or_fail(board_);
  ASSERT_EQ(send_request(board_, proto::Command::kGetInfo, 7), OutResult::kAck);
  ASSERT_TRUE(board_.usb().in_packet_waiting(0x81));
  EXPECT_FALSE(request(0x02, 1, 0, 0x81, 0).stalled);  // CLEAR_FEATURE(halt), not halted
  auto reply = read_report(board_);
  ASSERT_TRUE(reply.has_value());
  EXPECT_EQ(proto::peek_header(*reply).sequence, 7);
  ASSERT_EQ(send_request(board_, proto::Command::kGetInfo, 8), OutResult::kAck);
  EXPECT_FALSE(request(0x01, 11, 0, 0, 0).stalled);  // SET_INTERFACE(0, alt 0)
  reply = read_report(board_);
  ASSERT_TRUE(reply.has_value());
  EXPECT_EQ(proto::peek_header(*reply).sequence, 8);
  EXPECT_EQ(send_request(board_, proto::Command::kGetInfo, 9), OutResult::kAck);
  EXPECT_EQ(proto::peek_header(*read_report(board_)).sequence, 9);
}

TEST_F(UsbDeviceTest, BusResetUnconfiguresAndTurnsLedsOff) {
  enumerate_or_fail(board_);
  Controller& c = *board_.controller();
  // Light an LED through the self test and reset the bus halfway.
  proto::SelfTestRequest st{};
  st.step_time_us = 10'000;
  ASSERT_EQ(send_request(board_, proto::Command::kSelfTest, 1, st), OutResult::kAck);
  board_.run_for(5'000);
  EXPECT_NE(board_.port().led_mask(), 0);
  board_.bus_reset();
  EXPECT_EQ(board_.port().led_mask(), 0);
  EXPECT_EQ(c.state(), proto::ControllerState::kIdle);
  EXPECT_EQ(board_.application()->device().state(), usb::DeviceState::kDefault);
  EXPECT_FALSE(board_.usb().endpoint_open(0x81));
  board_.run_for(50'000);
  EXPECT_EQ(board_.port().led_mask(), 0);
  // The stale reply to the request before the reset is gone.
  enumerate_or_fail(board_);
  EXPECT_FALSE(read_report(board_).has_value());
}

}  // namespace
}  // namespace flutterscan::firmware::test
