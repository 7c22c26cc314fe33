// The v4l2 backend behind the CameraSource interface ("v4l2:/dev/video0"
// through the backend registry) against the umockdev fake V4L2 device
// (v4l2_fake_device.hpp): settings mapped and read back, refusals naming the
// setting, owned frames with 64-bit sequence numbers, dropped-frame counters,
// and the camera listing. Label: hil.

#include "capture/v4l2_source.hpp"

#include <gtest/gtest.h>

#include "v4l2_fake_device.hpp"

namespace flutterscan::capture {
namespace {

using testing::FakeDeviceConfig;
using testing::FakeV4l2Device;
using testing::pattern_byte;

std::unique_ptr<CameraSource> make(const std::string& spec, CameraContext context = {}) {
  std::string error;
  auto camera = make_camera(spec, context, error);
  EXPECT_NE(camera, nullptr) << error;
  return camera;
}

CameraSettings rgb_settings() {
  CameraSettings settings;
  settings.width = 64;
  settings.height = 48;
  settings.pixel_format = PixelFormat::kRgb8;
  return settings;
}

TEST(V4l2Source, StreamsOwnedFramesWithSequenceGapsCounted) {
  FakeDeviceConfig config;
  config.sequence_gaps = {{2, 1}};
  FakeV4l2Device device(config);
  CameraContext context;
  context.options = {{"gain", "40"}, {"io", "userptr"}};
  auto camera = make("v4l2:/dev/video0", context);
  ASSERT_NE(camera, nullptr);
  EXPECT_EQ(camera->name(), "v4l2:/dev/video0");
  ASSERT_EQ(camera->open(), "");
  CameraSettings wanted = rgb_settings();
  wanted.exposure_us = 1500;
  wanted.frame_rate_hz = 15;
  ASSERT_EQ(camera->configure(wanted), "");
  const CameraSettings got = camera->settings();
  EXPECT_EQ(got.pixel_format, PixelFormat::kRgb8);
  EXPECT_EQ(got.exposure_us, 1500.0);
  EXPECT_EQ(got.frame_rate_hz, 15.0);
  EXPECT_FALSE(got.auto_exposure || got.auto_gain || got.auto_white_balance);
  EXPECT_EQ(device.control_value(V4L2_CID_GAIN), 40);
  EXPECT_EQ(camera->format().row_bytes, 64u * 3);

  ASSERT_EQ(camera->start(), "");
  const std::uint64_t expected[] = {0, 1, 3, 4, 5};
  for (std::uint64_t sequence : expected) {
    Frame frame;
    std::string error;
    ASSERT_EQ(camera->next_frame(frame, std::chrono::milliseconds(1000), error), FrameWait::kFrame)
        << error;
    EXPECT_EQ(frame.sequence, sequence);
    EXPECT_EQ(frame.format.width, 64);
    ASSERT_EQ(frame.data.size(), 64u * 48 * 3);
    EXPECT_EQ(frame.data[100], pattern_byte(static_cast<std::uint32_t>(sequence), 100));
    EXPECT_GT(frame.host_arrival_ns, 0);
  }
  const CameraCounters counters = camera->counters();
  EXPECT_EQ(counters.frames_delivered, 5u);
  EXPECT_EQ(counters.frames_dropped, 1u);
  EXPECT_EQ(counters.incomplete_frames, 0u);
  camera->stop();
  EXPECT_FALSE(device.streaming());
}

TEST(V4l2Source, DefaultFormatIsRawRggbWithItsBitDepth) {
  FakeV4l2Device device(FakeDeviceConfig{});
  auto camera = make("v4l2:/dev/video0");
  ASSERT_NE(camera, nullptr);
  ASSERT_EQ(camera->open(), "");
  ASSERT_EQ(camera->configure(CameraSettings{}), "");
  EXPECT_EQ(camera->format().pixel_format, PixelFormat::kBayerRggb16);
  EXPECT_EQ(camera->format().bit_depth, 10);
}

TEST(V4l2Source, RefusesWhatV4l2CannotDoNamingTheSetting) {
  FakeV4l2Device device(FakeDeviceConfig{});
  auto camera = make("v4l2:/dev/video0");
  ASSERT_NE(camera, nullptr);
  ASSERT_EQ(camera->open(), "");
  CameraSettings trigger = rgb_settings();
  trigger.trigger = TriggerMode::kLine0;
  EXPECT_NE(camera->configure(trigger).find("trigger line0 refused"), std::string::npos);
  CameraSettings gain = rgb_settings();
  gain.gain_db = 6.0;
  EXPECT_NE(camera->configure(gain).find("gain_db refused"), std::string::npos);
  CameraSettings rgb16 = rgb_settings();
  rgb16.pixel_format = PixelFormat::kRgb16;
  EXPECT_NE(camera->configure(rgb16).find("rgb16 has no V4L2 equivalent"), std::string::npos);
  CameraSettings mono = rgb_settings();
  mono.pixel_format = PixelFormat::kMono8;
  EXPECT_NE(camera->configure(mono).find("GREY is not offered"), std::string::npos);
}

TEST(V4l2Source, YuyvWarningReachesTheInterface) {
  FakeV4l2Device device(FakeDeviceConfig{});
  auto camera = make("v4l2:/dev/video0");
  ASSERT_NE(camera, nullptr);
  ASSERT_EQ(camera->open(), "");
  CameraSettings yuyv = rgb_settings();
  yuyv.pixel_format = PixelFormat::kYuyv;
  ASSERT_EQ(camera->configure(yuyv), "");
  bool named = false;
  for (const std::string& warning : camera->warnings()) {
    named = named || warning.find("YUYV mixes") != std::string::npos;
  }
  EXPECT_TRUE(named);
}

TEST(V4l2Source, BadOptionsAndMissingNodeAreRefused) {
  FakeV4l2Device device(FakeDeviceConfig{});
  std::string error;
  CameraContext context;
  context.options = {{"buffers", "2"}};
  EXPECT_EQ(make_camera("v4l2:/dev/video0", context, error), nullptr);
  EXPECT_NE(error.find("option buffers=2: buffers is 4..32"), std::string::npos) << error;
  context.options = {{"exposure", "10"}};
  EXPECT_EQ(make_camera("v4l2:/dev/video0", context, error), nullptr);
  EXPECT_NE(error.find("unknown"), std::string::npos) << error;
  EXPECT_EQ(make_camera("v4l2", {}, error), nullptr);
  EXPECT_NE(error.find("give the device node"), std::string::npos) << error;
  auto missing = make("v4l2:/dev/video5");
  ASSERT_NE(missing, nullptr);
  EXPECT_NE(missing->open().find("cannot open /dev/video5"), std::string::npos);
}

TEST(V4l2Source, ListsTheFakeCamera) {
  FakeV4l2Device device(FakeDeviceConfig{});
  const std::vector<CameraInfo> cameras = list_v4l2_cameras();
  ASSERT_EQ(cameras.size(), 1u);
  EXPECT_EQ(cameras[0].spec, "v4l2:/dev/video0");
  EXPECT_NE(cameras[0].description.find("Fake V4L2 camera"), std::string::npos);
  EXPECT_EQ(cameras[0].pixel_formats, (std::vector<std::string>{"bayer-rggb16", "rgb8", "yuyv"}));
  EXPECT_EQ(cameras[0].features.front(), "exposure");
}

}  // namespace
}  // namespace flutterscan::capture
