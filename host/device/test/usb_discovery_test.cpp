// Choosing a controller among those found: by serial, the only one, or a
// clear refusal that lists them.
#include "device/usb_discovery.hpp"

#include <gtest/gtest.h>

namespace flutterscan::device {
namespace {

FoundDevice app(std::string serial) {
  FoundDevice device;
  device.mode = DeviceMode::kApplication;
  device.serial = std::move(serial);
  device.product = "flutterscan LED controller";
  return device;
}

FoundDevice dfu(std::string serial) {
  FoundDevice device = app(std::move(serial));
  device.mode = DeviceMode::kBootloader;
  device.product = "flutterscan DFU bootloader";
  return device;
}

TEST(PickController, TheOnlyOneWithoutASerial) {
  const auto picked =
      pick_controller({app("AAA"), dfu("BBB")}, std::nullopt, DeviceMode::kApplication);
  ASSERT_TRUE(picked.ok());
  EXPECT_EQ(picked.value().serial, "AAA");
}

TEST(PickController, BySerial) {
  const auto picked =
      pick_controller({app("AAA"), app("BBB")}, std::string("BBB"), DeviceMode::kApplication);
  ASSERT_TRUE(picked.ok());
  EXPECT_EQ(picked.value().serial, "BBB");
}

TEST(PickController, SeveralAndNoneNamedListsThem) {
  const auto picked =
      pick_controller({app("AAA"), app("BBB")}, std::nullopt, DeviceMode::kApplication);
  ASSERT_FALSE(picked.ok());
  EXPECT_EQ(picked.error().kind, ErrorKind::kAmbiguous);
  const std::string& message = picked.error().message;
  EXPECT_NE(message.find("2 controllers in application mode are connected and none was named"),
            std::string::npos)
      << message;
  EXPECT_NE(message.find("AAA"), std::string::npos);
  EXPECT_NE(message.find("BBB"), std::string::npos);
}

TEST(PickController, NoneOrUnknownSerial) {
  const auto none = pick_controller({}, std::nullopt, DeviceMode::kApplication);
  ASSERT_FALSE(none.ok());
  EXPECT_EQ(none.error().kind, ErrorKind::kNotFound);
  EXPECT_EQ(none.error().message, "no controller in application mode is connected");
  const auto unknown = pick_controller({app("AAA")}, std::string("CCC"), DeviceMode::kApplication);
  ASSERT_FALSE(unknown.ok());
  EXPECT_NE(unknown.error().message.find("no controller with serial number CCC"),
            std::string::npos);
  EXPECT_NE(unknown.error().message.find("AAA"), std::string::npos);
  // A controller in DFU mode is not an application-mode one.
  EXPECT_FALSE(pick_controller({dfu("AAA")}, std::string("AAA"), DeviceMode::kApplication).ok());
  EXPECT_TRUE(pick_controller({dfu("AAA")}, std::string("AAA"), DeviceMode::kBootloader).ok());
}

TEST(FindControllers, WithoutUsbDevicesFindsNone) {
  // This machine kind has no USB controllers; the call must not fail or crash.
  const auto found = find_controllers();
  if (!found.ok()) GTEST_SKIP() << "USB not enumerable here: " << found.error().message;
  for (const auto& device : found.value())
    EXPECT_FALSE(device.serial.empty() && device.problem.empty());
}

}  // namespace
}  // namespace flutterscan::device
