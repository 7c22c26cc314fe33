// The Aravis backend against Aravis's in-process fake GenICam camera: settings
// read back, software trigger, frame ids and timestamps, and a frame-id gap.
#include "capture/aravis_camera.hpp"

#include <gtest/gtest.h>

#include <arv.h>

namespace flutterscan::capture {
namespace {

using namespace std::chrono_literals;

/// The fake camera, opened and configured for software trigger at 320x240 RGB8;
/// skips (77) if Aravis cannot create it.
std::unique_ptr<CameraSource> open_fake(TriggerMode trigger) {
  std::string error;
  auto camera = make_camera("aravis:Fake_1", {}, error);
  EXPECT_TRUE(camera) << error;
  if (!camera) return nullptr;
  if (auto problem = camera->open(); !problem.empty()) {
    std::cerr << "Aravis's fake camera cannot be created: " << problem << "\n";
    std::exit(77);
  }
  CameraSettings wanted;
  wanted.width = 320;
  wanted.height = 240;
  wanted.pixel_format = PixelFormat::kRgb8;
  wanted.exposure_us = 5000;
  wanted.trigger = trigger;
  const std::string problem = camera->configure(wanted);
  EXPECT_EQ(problem, "");
  return camera;
}

Frame triggered_frame(CameraSource& camera) {
  EXPECT_EQ(camera.trigger(), "");
  Frame frame;
  std::string error;
  EXPECT_EQ(camera.next_frame(frame, 2000ms, error), FrameWait::kFrame) << error;
  return frame;
}

TEST(AravisCamera, ConfigureReadsTheSettingsBack) {
  auto camera = open_fake(TriggerMode::kSoftware);
  ASSERT_TRUE(camera);
  const CameraSettings s = camera->settings();
  EXPECT_EQ(s.width, 320);
  EXPECT_EQ(s.height, 240);
  EXPECT_EQ(s.pixel_format, PixelFormat::kRgb8);
  ASSERT_TRUE(s.exposure_us.has_value());
  EXPECT_NEAR(*s.exposure_us, 5000, 1);
  EXPECT_FALSE(s.auto_gain);  // the fake has GainAuto: it must read Off
  EXPECT_FALSE(s.auto_exposure);
  EXPECT_EQ(camera->format().row_bytes, 320u * 3u);
}

TEST(AravisCamera, SoftwareTriggerReachesTheCameraAndFramesKeepTheirIds) {
  auto camera = open_fake(TriggerMode::kSoftware);
  ASSERT_TRUE(camera);
  EXPECT_EQ(camera->settings().trigger, TriggerMode::kSoftware);  // read back from the camera
  ASSERT_EQ(camera->start(), "");
  EXPECT_EQ(take_fake_software_trigger(*camera), false);
  const Frame first = triggered_frame(*camera);
  // The fake records exactly one TriggerSoftware per trigger() (it keeps
  // streaming at its own rate regardless: Aravis 0.8.26's in-process fake).
  EXPECT_EQ(take_fake_software_trigger(*camera), true);
  EXPECT_EQ(take_fake_software_trigger(*camera), false);
  const Frame second = triggered_frame(*camera);
  const Frame third = triggered_frame(*camera);
  EXPECT_EQ(second.sequence, first.sequence + 1);
  EXPECT_EQ(third.sequence, second.sequence + 1);
  EXPECT_LT(first.timestamp_ns, second.timestamp_ns);
  EXPECT_LT(second.timestamp_ns, third.timestamp_ns);
  EXPECT_EQ(third.format.width, 320);
  EXPECT_EQ(third.format.pixel_format, PixelFormat::kRgb8);
  EXPECT_EQ(third.data.size(), 320u * 240u * 3u);
  EXPECT_EQ(camera->counters().frames_delivered, 3u);
  EXPECT_EQ(camera->counters().frames_dropped, 0u);
  camera->stop();
  camera->stop();  // twice is fine
}

TEST(AravisCamera, AFrameIdGapCountsAsDropped) {
  auto camera = open_fake(TriggerMode::kSoftware);
  ASSERT_TRUE(camera);
  ASSERT_EQ(camera->start(), "");
  const Frame before = triggered_frame(*camera);
  ASSERT_EQ(lose_one_fake_frame(*camera), "");
  const Frame after = triggered_frame(*camera);
  EXPECT_EQ(after.sequence, before.sequence + 2);
  EXPECT_EQ(camera->counters().frames_dropped, 1u);
  EXPECT_EQ(camera->counters().frames_delivered, 2u);
}

TEST(AravisCamera, Line0TriggerReadsBackAndFreeRunClearsIt) {
  auto camera = open_fake(TriggerMode::kLine0);
  ASSERT_TRUE(camera);
  EXPECT_EQ(camera->settings().trigger, TriggerMode::kLine0);
  CameraSettings free_run;
  free_run.trigger = TriggerMode::kFreeRun;
  ASSERT_EQ(camera->configure(free_run), "");
  EXPECT_EQ(camera->settings().trigger, TriggerMode::kFreeRun);
}

TEST(AravisCamera, UnknownDeviceIsRefusedNamingIt) {
  std::string error;
  auto camera = make_camera("aravis:No-Such-Camera-42", {}, error);
  ASSERT_TRUE(camera);
  const std::string problem = camera->open();
  EXPECT_NE(problem.find("aravis:No-Such-Camera-42"), std::string::npos) << problem;
}

TEST(AravisCamera, ListsTheFakeCamera) {
  arv_enable_interface("Fake");
  bool found = false;
  for (const auto& backend : camera_backends())
    if (backend.scheme == "aravis")
      for (const auto& info : backend.list())
        if (info.spec == "aravis:Fake_1") {
          found = true;
          EXPECT_FALSE(info.pixel_formats.empty());
        }
  EXPECT_TRUE(found);
}

}  // namespace
}  // namespace flutterscan::capture
