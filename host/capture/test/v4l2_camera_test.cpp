// The v4l2 backend's core (V4l2Camera) against a fake V4L2 device answered by
// a umockdev ioctl handler (v4l2_fake_device.hpp). The backend's real open()
// and ioctl() calls go through umockdev's preload library; nothing in the
// backend is mocked. Covered: the control path (QUERYCAP, ENUM_FMT, S_FMT,
// S_PARM, controls with read-back, refusals naming the setting), the MMAP ->
// USERPTR fallback (mmap on a mocked node fails with ENODEV), and USERPTR
// streaming with frame contents, timestamps, a dropped-frame sequence gap, a
// buffer flagged as an error, and a stalled camera (a bounded wait: poll()
// never reports readiness on mocked nodes). Label: hil.

#include "capture/v4l2_camera.hpp"

#include <gtest/gtest.h>

#include <chrono>

#include "v4l2_fake_device.hpp"

namespace flutterscan::capture {
namespace {

using testing::FakeControl;
using testing::FakeDeviceConfig;
using testing::FakeV4l2Device;
using testing::pattern_byte;

std::unique_ptr<V4l2Camera> open_camera(const FakeV4l2Device& device) {
  auto opened = V4l2Camera::open(device.path());
  EXPECT_TRUE(opened.ok()) << opened.error();
  return opened.ok() ? std::move(opened.value()) : nullptr;
}

V4l2Config rgb_config() {
  V4l2Config config;
  config.width = 64;
  config.height = 48;
  config.fourccs = {V4L2_PIX_FMT_RGB24};
  return config;
}

bool contains(const std::vector<std::string>& texts, const std::string& part) {
  for (const std::string& text : texts) {
    if (text.find(part) != std::string::npos) return true;
  }
  return false;
}

TEST(V4l2Camera, OpenReadsCapabilitiesAndFormats) {
  FakeV4l2Device device(FakeDeviceConfig{});
  auto camera = open_camera(device);
  ASSERT_NE(camera, nullptr);
  EXPECT_EQ(camera->description().driver, "fakecam");
  EXPECT_EQ(camera->description().card, "Fake V4L2 camera");
  EXPECT_EQ(
      camera->description().offered_fourccs,
      (std::vector<std::uint32_t>{V4L2_PIX_FMT_SRGGB10, V4L2_PIX_FMT_RGB24, V4L2_PIX_FMT_YUYV}));
  EXPECT_EQ(camera->control_features(),
            (std::vector<std::string>{"exposure", "gain", "gamma", "auto exposure", "auto gain",
                                      "auto white balance"}));
}

TEST(V4l2Camera, ConfigureSetsFormatRateExposureGainAndTurnsAutomaticsOff) {
  FakeV4l2Device device(FakeDeviceConfig{});
  auto camera = open_camera(device);
  ASSERT_NE(camera, nullptr);
  V4l2Config config = rgb_config();
  config.frame_rate = 15;
  config.controls.exposure_us = 2000;
  config.controls.gain = 40;
  ASSERT_EQ(camera->configure(config), "");
  const V4l2Description& d = camera->description();
  EXPECT_EQ(d.format.info.fourcc, V4L2_PIX_FMT_RGB24);
  EXPECT_EQ(d.format.width, 64);
  EXPECT_EQ(d.format.height, 48);
  EXPECT_EQ(d.format.bytes_per_line, 64u * 3);
  EXPECT_DOUBLE_EQ(d.format.frame_rate, 15.0);
  ASSERT_TRUE(d.controls.exposure_us.has_value());
  EXPECT_DOUBLE_EQ(*d.controls.exposure_us, 2000.0);
  EXPECT_EQ(d.controls.gain, 40);
  // The device itself holds the values (exposure in 100 us units).
  EXPECT_EQ(device.control_value(V4L2_CID_EXPOSURE_AUTO), V4L2_EXPOSURE_MANUAL);
  EXPECT_EQ(device.control_value(V4L2_CID_EXPOSURE_ABSOLUTE), 20);
  EXPECT_EQ(device.control_value(V4L2_CID_AUTOGAIN), 0);
  EXPECT_EQ(device.control_value(V4L2_CID_GAIN), 40);
  EXPECT_EQ(device.control_value(V4L2_CID_AUTO_WHITE_BALANCE), 0);
  // Gamma exists but its linear value is driver-specific: a warning, not a guess.
  EXPECT_TRUE(contains(d.controls.warnings, "gamma control present"));
  EXPECT_EQ(device.control_value(V4L2_CID_GAMMA), 100);
}

TEST(V4l2Camera, GammaIsSetWhenGiven) {
  FakeV4l2Device device(FakeDeviceConfig{});
  auto camera = open_camera(device);
  ASSERT_NE(camera, nullptr);
  V4l2Config config = rgb_config();
  config.controls.gamma = 220;
  ASSERT_EQ(camera->configure(config), "");
  EXPECT_EQ(device.control_value(V4L2_CID_GAMMA), 220);
  EXPECT_FALSE(contains(camera->description().controls.warnings, "gamma"));
}

TEST(V4l2Camera, DefaultFormatIsTheDeepestRawBayerOffered) {
  FakeV4l2Device device(FakeDeviceConfig{});
  auto camera = open_camera(device);
  ASSERT_NE(camera, nullptr);
  V4l2Config config;
  ASSERT_EQ(camera->configure(config), "");
  const V4l2Format& format = camera->description().format;
  EXPECT_EQ(format.info.fourcc, V4L2_PIX_FMT_SRGGB10);
  EXPECT_EQ(format.info.bits_per_sample, 10);
  EXPECT_EQ(format.info.bayer_order, "RGGB");
  EXPECT_EQ(format.width, 64);  // the driver's current size was kept
  EXPECT_TRUE(camera->description().warnings.empty());
}

TEST(V4l2Camera, YuyvIsAcceptedWithAWarningNamingTheAccuracyLost) {
  FakeV4l2Device device(FakeDeviceConfig{});
  auto camera = open_camera(device);
  ASSERT_NE(camera, nullptr);
  V4l2Config config = rgb_config();
  config.fourccs = {V4L2_PIX_FMT_YUYV};
  ASSERT_EQ(camera->configure(config), "");
  ASSERT_EQ(camera->description().warnings.size(), 1u);
  EXPECT_NE(camera->description().warnings[0].find("YUYV mixes R, G and B"), std::string::npos);
}

TEST(V4l2Camera, RefusesAFormatTheDeviceDoesNotOffer) {
  FakeV4l2Device device(FakeDeviceConfig{});
  auto camera = open_camera(device);
  ASSERT_NE(camera, nullptr);
  V4l2Config config = rgb_config();
  config.fourccs = {V4L2_PIX_FMT_BGR24};
  const std::string error = camera->configure(config);
  EXPECT_NE(error.find("BGR3 is not offered (offers: RG10 RGB3 YUYV)"), std::string::npos) << error;
}

TEST(V4l2Camera, RefusesASizeTheDriverChanges) {
  FakeV4l2Device device(FakeDeviceConfig{});
  auto camera = open_camera(device);
  ASSERT_NE(camera, nullptr);
  V4l2Config config = rgb_config();
  config.width = 4000;
  config.height = 3000;
  const std::string error = camera->configure(config);
  EXPECT_NE(error.find("frame size 4000x3000 requested, driver set 1920x1080"), std::string::npos)
      << error;
}

TEST(V4l2Camera, RefusesAFrameRateTheDriverCannotMeet) {
  FakeV4l2Device device(FakeDeviceConfig{});
  auto camera = open_camera(device);
  ASSERT_NE(camera, nullptr);
  V4l2Config config = rgb_config();
  config.frame_rate = 25;
  const std::string error = camera->configure(config);
  EXPECT_NE(error.find("frame rate 25"), std::string::npos) << error;
  EXPECT_NE(error.find("driver set 30"), std::string::npos) << error;
}

TEST(V4l2Camera, RefusesToStartWhenAutoExposureStaysOn) {
  FakeDeviceConfig config;
  for (FakeControl& control : config.controls) {
    if (control.id == V4L2_CID_EXPOSURE_AUTO) control.ignores_writes = true;
  }
  FakeV4l2Device device(config);
  auto camera = open_camera(device);
  ASSERT_NE(camera, nullptr);
  const std::string error = camera->configure(rgb_config());
  EXPECT_NE(error.find("auto exposure (control \"Auto Exposure\") set to 1 but reads back 3"),
            std::string::npos)
      << error;
  EXPECT_NE(camera->start(), "");  // never configured: no streaming
}

TEST(V4l2Camera, RefusesGainOutsideTheControlRange) {
  FakeV4l2Device device(FakeDeviceConfig{});
  auto camera = open_camera(device);
  ASSERT_NE(camera, nullptr);
  V4l2Config config = rgb_config();
  config.controls.gain = 300;
  const std::string error = camera->configure(config);
  EXPECT_NE(error.find("gain 300 is outside the camera's range 0..255"), std::string::npos)
      << error;
}

TEST(V4l2Camera, MissingControlsRefuseWhenAskedForAndWarnOtherwise) {
  FakeDeviceConfig config;
  config.controls = {{V4L2_CID_GAIN, "Gain", V4L2_CTRL_TYPE_INTEGER, 0, 255, 1, 32, 32, false}};
  {
    FakeV4l2Device device(config);
    auto camera = open_camera(device);
    ASSERT_NE(camera, nullptr);
    V4l2Config wanted = rgb_config();
    wanted.controls.exposure_us = 1000;
    const std::string error = camera->configure(wanted);
    EXPECT_NE(error.find("no absolute exposure control"), std::string::npos) << error;
  }
  FakeV4l2Device device(config);
  auto camera = open_camera(device);
  ASSERT_NE(camera, nullptr);
  ASSERT_EQ(camera->configure(rgb_config()), "");
  const auto& warnings = camera->description().controls.warnings;
  EXPECT_TRUE(contains(warnings, "no auto exposure control"));
  EXPECT_TRUE(contains(warnings, "no auto gain control"));
  EXPECT_TRUE(contains(warnings, "no auto white balance control"));
  EXPECT_TRUE(contains(warnings, "no gamma control"));
  EXPECT_TRUE(contains(warnings, "no absolute exposure control"));
}

TEST(V4l2Camera, RefusesADeviceWithoutStreamingIo) {
  FakeDeviceConfig config;
  config.device_caps = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_READWRITE;
  FakeV4l2Device device(config);
  auto opened = V4l2Camera::open(device.path());
  ASSERT_FALSE(opened.ok());
  EXPECT_NE(opened.error().find("does not support streaming I/O"), std::string::npos)
      << opened.error();
}

TEST(V4l2Camera, RefusesAMissingNode) {
  FakeV4l2Device device(FakeDeviceConfig{});
  auto opened = V4l2Camera::open("/dev/video7");
  ASSERT_FALSE(opened.ok());
  EXPECT_NE(opened.error().find("cannot open /dev/video7"), std::string::npos) << opened.error();
}

/// Captures `count` frames, checking each frame's bytes against the fake's pattern.
std::vector<V4l2Frame> capture(V4l2Camera& camera, int count) {
  std::vector<V4l2Frame> frames;
  for (int i = 0; i < count; ++i) {
    V4l2Frame frame;
    std::string error;
    const V4l2Wait got = camera.next_frame(frame, 1000, error);
    EXPECT_EQ(got, V4l2Wait::kFrame) << "frame " << i << ": " << error;
    if (got != V4l2Wait::kFrame) break;
    EXPECT_EQ(frame.data.size(), 64u * 48 * 3);
    bool matches = true;
    for (std::size_t b = 0; b < frame.data.size(); ++b) {
      matches = matches && frame.data[b] == pattern_byte(frame.sequence, b);
    }
    EXPECT_TRUE(matches) << "frame " << i << " (sequence " << frame.sequence << ") has other bytes";
    frame.data = {};  // the buffer is reused
    frames.push_back(frame);
  }
  return frames;
}

TEST(V4l2Camera, FallsBackToUserptrAndCountsADroppedFrameGap) {
  FakeDeviceConfig config;
  config.sequence_gaps = {{3, 2}};  // the 4th delivered frame comes 2 sequence numbers late
  FakeV4l2Device device(config);
  auto camera = open_camera(device);
  ASSERT_NE(camera, nullptr);
  ASSERT_EQ(camera->configure(rgb_config()), "");
  ASSERT_EQ(camera->start(), "");
  // MMAP was tried first; mmap() of a mocked node fails, so USERPTR streams.
  EXPECT_EQ(device.buffer_requests(V4L2_MEMORY_MMAP), 1);
  EXPECT_EQ(device.buffer_requests(V4L2_MEMORY_USERPTR), 1);
  EXPECT_EQ(camera->io_method(), V4l2IoMethod::kUserPtr);
  EXPECT_TRUE(contains(camera->description().warnings, "streaming with USERPTR instead"));
  EXPECT_TRUE(device.streaming());

  const std::vector<V4l2Frame> frames = capture(*camera, 8);
  ASSERT_EQ(frames.size(), 8u);
  const std::uint32_t expected[] = {0, 1, 2, 5, 6, 7, 8, 9};
  for (std::size_t i = 0; i < frames.size(); ++i) {
    EXPECT_EQ(frames[i].sequence, expected[i]);
    EXPECT_EQ(frames[i].index, i);
    EXPECT_EQ(frames[i].dropped_before, i == 3 ? 2u : 0u);
    EXPECT_EQ(frames[i].clock, V4l2Clock::kMonotonic);
    EXPECT_EQ(frames[i].timestamp_source, V4l2TimestampSource::kStartOfExposure);
    // 1 s + sequence * 33.333333 ms, in whole microseconds.
    EXPECT_EQ(frames[i].timestamp_ns, (1'000'000'000LL + expected[i] * 33'333'333LL) / 1000 * 1000);
  }
  EXPECT_EQ(camera->stats().frames, 8u);
  EXPECT_EQ(camera->stats().dropped, 2u);
  EXPECT_EQ(camera->stats().corrupt, 0u);
  camera->stop();
  EXPECT_FALSE(device.streaming());
}

TEST(V4l2Camera, RestartsAfterStopWithFreshCounters) {
  FakeV4l2Device device(FakeDeviceConfig{});
  auto camera = open_camera(device);
  ASSERT_NE(camera, nullptr);
  ASSERT_EQ(camera->configure(rgb_config()), "");
  for (int run = 0; run < 2; ++run) {
    ASSERT_EQ(camera->start(), "") << "run " << run;
    const std::vector<V4l2Frame> frames = capture(*camera, 3);
    ASSERT_EQ(frames.size(), 3u);
    EXPECT_EQ(frames[0].sequence, 0u);
    EXPECT_EQ(camera->stats().frames, 3u);
    EXPECT_EQ(camera->stats().dropped, 0u);
    camera->stop();
  }
  EXPECT_EQ(device.buffer_requests(V4L2_MEMORY_USERPTR), 2);
  int fallback_warnings = 0;
  for (const std::string& warning : camera->description().warnings) {
    fallback_warnings += warning.find("USERPTR instead") != std::string::npos ? 1 : 0;
  }
  EXPECT_EQ(fallback_warnings, 1);
}

TEST(V4l2Camera, UserptrOnRequestSkipsMmap) {
  FakeV4l2Device device(FakeDeviceConfig{});
  auto camera = open_camera(device);
  ASSERT_NE(camera, nullptr);
  V4l2Config config = rgb_config();
  config.io = V4l2IoMethod::kUserPtr;
  ASSERT_EQ(camera->configure(config), "");
  ASSERT_EQ(camera->start(), "");
  EXPECT_EQ(device.buffer_requests(V4L2_MEMORY_MMAP), 0);
  EXPECT_EQ(capture(*camera, 6).size(), 6u);  // more frames than buffers: requeueing works
  EXPECT_EQ(camera->stats().dropped, 0u);
}

TEST(V4l2Camera, MmapOnlyFailsNamingMmap) {
  FakeV4l2Device device(FakeDeviceConfig{});
  auto camera = open_camera(device);
  ASSERT_NE(camera, nullptr);
  V4l2Config config = rgb_config();
  config.io = V4l2IoMethod::kMmap;
  ASSERT_EQ(camera->configure(config), "");
  const std::string error = camera->start();
  EXPECT_NE(error.find("mmap of buffer 0 failed"), std::string::npos) << error;
}

TEST(V4l2Camera, ABufferFlaggedAsErrorIsCountedNotDelivered) {
  FakeDeviceConfig config;
  config.error_frames = {2};
  FakeV4l2Device device(config);
  auto camera = open_camera(device);
  ASSERT_NE(camera, nullptr);
  ASSERT_EQ(camera->configure(rgb_config()), "");
  ASSERT_EQ(camera->start(), "");
  const std::vector<V4l2Frame> frames = capture(*camera, 4);
  ASSERT_EQ(frames.size(), 4u);
  EXPECT_EQ(frames[2].sequence, 3u);
  EXPECT_EQ(frames[2].dropped_before, 0u);  // its sequence number arrived, broken
  EXPECT_EQ(camera->stats().corrupt, 1u);
  EXPECT_EQ(camera->stats().dropped, 0u);
}

TEST(V4l2Camera, AStalledCameraTimesOutWithinTheBound) {
  FakeDeviceConfig config;
  config.stall_after = 2;
  FakeV4l2Device device(config);
  auto camera = open_camera(device);
  ASSERT_NE(camera, nullptr);
  ASSERT_EQ(camera->configure(rgb_config()), "");
  ASSERT_EQ(camera->start(), "");
  EXPECT_EQ(capture(*camera, 2).size(), 2u);
  V4l2Frame frame;
  std::string error;
  const auto started = std::chrono::steady_clock::now();
  EXPECT_EQ(camera->next_frame(frame, 300, error), V4l2Wait::kTimeout);
  const auto waited = std::chrono::steady_clock::now() - started;
  EXPECT_GE(waited, std::chrono::milliseconds(290));
  EXPECT_LT(waited, std::chrono::milliseconds(1500));
}

TEST(V4l2Camera, NextFrameBeforeStartIsAnError) {
  FakeV4l2Device device(FakeDeviceConfig{});
  auto camera = open_camera(device);
  ASSERT_NE(camera, nullptr);
  V4l2Frame frame;
  std::string error;
  EXPECT_EQ(camera->next_frame(frame, 10, error), V4l2Wait::kError);
  EXPECT_NE(error.find("before start()"), std::string::npos);
}

}  // namespace
}  // namespace flutterscan::capture
