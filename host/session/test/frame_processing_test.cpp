// A worker's work on one frame: a sim frame with a whole label in view is
// deblurred and its label read at its ground truth; a frame whose event does
// not fit the code is refused, logged, not processed.
#include "session/frame_processing.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>

#include "capture/sim_camera.hpp"
#include "device/controller_client.hpp"
#include "device/in_process_transport.hpp"
#include "device/virtual_controller.hpp"
#include "imaging/capture_descriptor.hpp"

namespace flutterscan::session {
namespace {

/// The session's defaults at 640x240 (the sim session tests' belt), checked.
SessionConfig small_config() {
  SessionConfig c;
  c.optics.px_per_count = 0.5;
  c.processing.threads_per_worker = 1;
  EXPECT_EQ(check_config(c), "");
  return c;
}

/// A sim frame with a whole label in view and the event that lit it (the
/// encoder's counts from the frame's own descriptor).
FrameJob job_with_a_label(const SessionConfig& config) {
  auto controller = std::make_shared<device::VirtualController>();
  auto client = device::ControllerClient::connect(device::in_process_opener(controller));
  EXPECT_TRUE(client.ok());
  protocol::SetTimingRequest timing{};
  timing.slot_time_us = config.controller.slot_time_us;
  EXPECT_TRUE(client.value()->set_code(0, config.controller.parsed_code, true).ok());
  EXPECT_TRUE(client.value()->select_code(0).ok());
  EXPECT_TRUE(client.value()->set_timing(timing).ok());
  EXPECT_TRUE(client.value()->arm().ok());
  capture::SimConveyorOptions belt;
  belt.width = 640;
  belt.height = 240;
  belt.gap = 100;
  belt.render_threads = 1;
  auto camera = capture::make_sim_camera(*controller, belt);
  EXPECT_EQ(camera->start(), "");
  FrameJob job;
  std::string error;
  for (int i = 0; i < 40 && (i < 4 || job.frame.truth.empty()); ++i)
    camera->next_frame(job.frame, std::chrono::milliseconds(1000), error);
  const auto model = imaging::from_descriptor(nlohmann::json::parse(job.frame.descriptor_json));
  EXPECT_TRUE(model.ok());
  job.index = 7;
  job.travel_px = 123;
  job.event.frame_counter = 8;
  job.event.slot_count = static_cast<std::uint16_t>(config.controller.parsed_code.length());
  job.event.slot_time_us = config.controller.slot_time_us;
  job.event.encoder_delta =
      static_cast<std::int32_t>(std::lround(model.value().blur_px / config.optics.px_per_count));
  return job;
}

TEST(FrameProcessing, AWholeLabelIsDeblurredAndReadAtItsGroundTruth) {
  const SessionConfig config = small_config();
  FrameJob job = job_with_a_label(config);
  ASSERT_FALSE(job.frame.truth.empty());
  const std::vector<std::string> truth = job.frame.truth;
  const std::uint64_t sequence = job.frame.sequence;
  std::atomic<double> last_blur_px{config.optics.nominal_blur_px};
  const FrameOutcome out = process_frame(job, config, last_blur_px, nullptr);
  ASSERT_TRUE(out.processed) << out.log.dump();
  EXPECT_EQ(out.index, 7u);
  EXPECT_EQ(out.sequence, sequence);
  EXPECT_EQ(out.travel_px, 123);
  EXPECT_EQ(out.truth, truth);
  for (const auto& value : truth)
    EXPECT_TRUE(std::any_of(out.sightings.begin(), out.sightings.end(),
                            [&](const Sighting& s) { return s.decoded && s.value == value; }))
        << value << " not read: " << out.log.dump();
  EXPECT_FALSE(out.decode_failed);
  for (const char* stage : {"convert", "deblur", "decode"})
    EXPECT_TRUE(out.log["times_ms"].contains(stage)) << stage;
  EXPECT_EQ(out.log["event"]["counter"], 8);
  EXPECT_EQ(out.descriptor["capture"]["sequence"], sequence);
  EXPECT_EQ(out.latent.width, 640);
  EXPECT_FALSE(out.frame.data.empty());  // kept for the results stage to save
}

TEST(FrameProcessing, AnEventThatDoesNotFitTheCodeIsLoggedNotProcessed) {
  const SessionConfig config = small_config();
  FrameJob job = job_with_a_label(config);
  job.event.slot_count = static_cast<std::uint16_t>(job.event.slot_count + 1);
  std::atomic<double> last_blur_px{config.optics.nominal_blur_px};
  const FrameOutcome out = process_frame(job, config, last_blur_px, nullptr);
  EXPECT_FALSE(out.processed);
  EXPECT_NE(out.log["error"].get<std::string>().find("exposure 8"), std::string::npos)
      << out.log.dump();
  EXPECT_EQ(out.log["flags"], nlohmann::json::array({"error"}));
  EXPECT_TRUE(out.sightings.empty());
}

/// `frame` (RGB16) as the raw RGGB mosaic (16-bit) a Bayer camera would give,
/// mirrored along x first when `mirror` is set.
void to_bayer_mosaic(capture::Frame& frame, bool mirror) {
  const int w = frame.format.width, h = frame.format.height;
  const std::size_t stride = frame.format.row_bytes != 0 ? frame.format.row_bytes : w * 6u;
  std::vector<std::uint8_t> mosaic(static_cast<std::size_t>(w) * h * 2);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const int channel = (y % 2) + (x % 2);  // R at (even, even), G, G, B at (odd, odd)
      const int from = mirror ? w - 1 - x : x;
      const std::size_t in = y * stride + static_cast<std::size_t>(from) * 6 + channel * 2;
      const std::size_t out = (static_cast<std::size_t>(y) * w + x) * 2;
      mosaic[out] = frame.data[in];
      mosaic[out + 1] = frame.data[in + 1];
    }
  frame.data = std::move(mosaic);
  frame.format.pixel_format = capture::PixelFormat::kBayerRggb16;
  frame.format.row_bytes = static_cast<std::size_t>(w) * 2;
}

TEST(FrameProcessing, ARawBayerFrameIsDeblurredOnItsPlanesAndReadInEitherDirection) {
  for (const bool mirror : {false, true}) {
    SessionConfig config = small_config();
    config.optics.direction = mirror ? "-x" : "+x";
    ASSERT_EQ(check_config(config), "");
    FrameJob job = job_with_a_label(config);
    ASSERT_FALSE(job.frame.truth.empty());
    const std::vector<std::string> truth = job.frame.truth;
    to_bayer_mosaic(job.frame, mirror);
    std::atomic<double> last_blur_px{config.optics.nominal_blur_px};
    const FrameOutcome out = process_frame(job, config, last_blur_px, nullptr);
    ASSERT_TRUE(out.processed) << out.log.dump();
    EXPECT_EQ(out.latent.width, 640);
    EXPECT_EQ(out.latent.height, 240);
    for (const auto& value : truth)
      EXPECT_TRUE(std::any_of(out.sightings.begin(), out.sightings.end(),
                              [&](const Sighting& s) { return s.decoded && s.value == value; }))
          << value << (mirror ? " (-x)" : " (+x)") << " not read: " << out.log.dump();
    EXPECT_GT(out.log["decode_windows"].get<int>(), 0) << out.log.dump();
  }
}

}  // namespace
}  // namespace flutterscan::session
