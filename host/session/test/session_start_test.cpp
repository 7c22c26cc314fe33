// Before the pipeline: inputs checked in turn (configuration, flat field, the
// sim line), each refusal naming what to change; the session folder's name.
#include "session/session_start.hpp"

#include <gtest/gtest.h>

#include <fstream>

#include "session/test/session_test_support.hpp"

namespace flutterscan::session {
namespace {

TEST(SessionStart, ASimCameraNeedsTheVirtualControllerInSlaveSync) {
  SessionConfig config;
  config.camera.spec = "sim";
  config.controller.spec = "auto";
  auto checked = check_session_inputs(config);
  ASSERT_FALSE(checked.ok());
  EXPECT_NE(checked.error().find("controller.spec = \"sim\""), std::string::npos);
  config.controller.spec = "sim";
  config.controller.sync = "master";
  config.controller.frame_period_us = 16'667;  // master sync: a valid configuration
  checked = check_session_inputs(config);
  ASSERT_FALSE(checked.ok());
  EXPECT_NE(checked.error().find("controller.sync must be \"slave\""), std::string::npos);
  config.controller.sync = "slave";
  checked = check_session_inputs(config);
  ASSERT_TRUE(checked.ok()) << checked.error();
  EXPECT_FALSE(checked.value().has_value());  // no flat field configured
}

TEST(SessionStart, AnUnreadableFlatFieldIsRefusedNamingTheFile) {
  testing::ScratchFolder scratch("start_flat_field");
  const auto path = scratch.path() / "flat.json";
  std::ofstream(path) << "{ not json";
  SessionConfig config;
  config.optics.flat_field = path.string();
  const auto checked = check_session_inputs(config);
  ASSERT_FALSE(checked.ok());
  EXPECT_EQ(checked.error(),
            "config: optics.flat_field '" + path.string() + "': not readable JSON");
}

TEST(SessionStart, ABadConfigurationIsRefusedFirst) {
  SessionConfig config;
  config.processing.workers = 0;
  config.camera.spec = "sim";
  config.controller.spec = "auto";  // also wrong, but the configuration is checked first
  const auto checked = check_session_inputs(config);
  ASSERT_FALSE(checked.ok());
  EXPECT_EQ(checked.error().rfind("config: ", 0), 0u) << checked.error();
}

TEST(SessionStart, TimestampedFoldersNeverReuseAName) {
  testing::ScratchFolder scratch("start_folder_names");
  OutputConfig output;
  output.dir = scratch.path().string();
  output.timestamped_subfolder = false;
  EXPECT_EQ(session_folder_name(output), output.dir);
  output.timestamped_subfolder = true;
  const std::string first = session_folder_name(output);
  EXPECT_EQ(std::filesystem::path(first).parent_path(), scratch.path());
  std::filesystem::create_directories(first);
  const std::string second = session_folder_name(output);
  EXPECT_NE(second, first);
}

}  // namespace
}  // namespace flutterscan::session
