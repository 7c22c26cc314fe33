// The line stage: the sim controller connected and set up with the session's
// code, timing and sync mode; the sim camera opened on it; specs and settings
// that name nothing usable refused as the user's input.
#include "session/line_devices.hpp"

#include <gtest/gtest.h>

#include "session/test/session_test_support.hpp"

namespace flutterscan::session {
namespace {

using testing::small_sim_config;

SessionConfig checked_sim_config() {
  SessionConfig config = small_sim_config("unused", 4);
  EXPECT_EQ(check_config(config), "");
  return config;
}

TEST(LineDevices, TheSimControllerIsConnectedAndSetUpForTheSession) {
  SessionConfig config = checked_sim_config();
  config.controller.sync = "master";
  config.controller.frame_period_us = 20'000;
  ControllerLink link;
  bool bad_input = false;
  ASSERT_EQ(connect_controller(config, {}, link, bad_input), "");
  EXPECT_FALSE(bad_input);
  ASSERT_NE(link.client, nullptr);
  ASSERT_NE(link.virtual_controller, nullptr);
  EXPECT_EQ(link.description, "virtual controller (firmware core on the sim port)");
  const auto status = link.client->status();
  ASSERT_TRUE(status.ok()) << status.error().message;
  EXPECT_EQ(status.value().state, static_cast<std::uint8_t>(protocol::ControllerState::kIdle));
  EXPECT_EQ(status.value().sync_mode, static_cast<std::uint8_t>(protocol::SyncMode::kMaster));
  EXPECT_EQ(status.value().active_code_id, 0);  // the session's code, selected
  EXPECT_EQ(status.value().codes_stored & 1, 1);
  EXPECT_EQ(status.value().slot_time_us, config.controller.slot_time_us);
}

TEST(LineDevices, TheHooksVirtualControllerIsTheOneUsed) {
  const SessionConfig config = checked_sim_config();
  SessionHooks hooks;
  hooks.virtual_controller = std::make_shared<device::VirtualController>();
  ControllerLink link;
  bool bad_input = false;
  ASSERT_EQ(connect_controller(config, hooks, link, bad_input), "");
  EXPECT_EQ(link.virtual_controller, hooks.virtual_controller);
}

TEST(LineDevices, TheSimCameraOpensOnTheVirtualController) {
  const SessionConfig config = checked_sim_config();
  device::VirtualController controller;
  std::string error;
  bool bad_input = false;
  const auto camera = open_camera(config.camera, &controller, error, bad_input);
  ASSERT_NE(camera, nullptr) << error;
  EXPECT_EQ(error, "");
  EXPECT_FALSE(bad_input);
  EXPECT_EQ(camera->format().width, 640);  // the config's conveyor options
  EXPECT_EQ(camera->format().height, 240);
}

TEST(LineDevices, CamerasThatCannotOpenAreRefusedNamingWhy) {
  SessionConfig config = checked_sim_config();
  std::string error;
  bool bad_input = false;
  // The sim camera without its virtual controller.
  EXPECT_EQ(open_camera(config.camera, nullptr, error, bad_input), nullptr);
  EXPECT_TRUE(bad_input);
  EXPECT_NE(error.find("virtual controller"), std::string::npos) << error;
  // A setting the camera refuses: the user's input, named as a [camera] setting.
  device::VirtualController controller;
  config.camera.settings.pixel_format = capture::PixelFormat::kMono8;
  error.clear();
  bad_input = false;
  EXPECT_EQ(open_camera(config.camera, &controller, error, bad_input), nullptr);
  EXPECT_TRUE(bad_input);
  EXPECT_EQ(error.rfind("[camera] settings: ", 0), 0u) << error;
}

TEST(LineDevices, AnExposureEventBecomesTheMatchersRecord) {
  device::EventNotice notice;
  notice.event.frame_counter = 7;
  notice.event.start_time_us = 123'456;
  notice.event.encoder_delta = -40;
  notice.event.slot_time_us = 100;
  notice.event.slot_count = 52;
  notice.event.code_id = 3;
  notice.event.flags = 1;
  const ExposureRecord r = exposure_record(notice);
  EXPECT_EQ(r.frame_counter, 7u);
  EXPECT_EQ(r.start_us, 123'456u);
  EXPECT_EQ(r.encoder_delta, -40);
  EXPECT_EQ(r.slot_time_us, 100u);
  EXPECT_EQ(r.slot_count, 52);
  EXPECT_EQ(r.code_id, 3);
  EXPECT_EQ(r.flags, 1);
}

}  // namespace
}  // namespace flutterscan::session
