// The sim conveyor: light from the virtual controller's actual LED
// transitions, blur from the belt speed, encoder counts in the exposure
// events, ground truth of the labels in view, lost frames counted.
#include "capture/sim_camera.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <vector>

#include "capture/frame_pixels.hpp"
#include "device/virtual_controller.hpp"
#include "flutterscan/common/protocol.hpp"
#include "imaging/capture_descriptor.hpp"

namespace flutterscan::capture {
namespace {

namespace proto = flutterscan::protocol;
using namespace std::chrono_literals;

constexpr std::string_view kCode = "2212441414112412441224111241244244242212442211444144";

device::Report request(device::VirtualController& vc, proto::Command command) {
  device::Report report{};
  proto::encode_request(command, 1, report);
  return vc.request(report);
}

template <typename T>
device::Report request(device::VirtualController& vc, proto::Command command, const T& payload) {
  device::Report report{};
  proto::encode_request(command, 1, payload, report);
  return vc.request(report);
}

/// Code 0 = kCode, 100 us slots, slave mode, armed.
void arm(device::VirtualController& vc) {
  proto::SetCodeRequest chunk{};
  chunk.led_count = 3;
  chunk.total_slots = static_cast<std::uint16_t>(kCode.size());
  chunk.slot_count = static_cast<std::uint8_t>(kCode.size());
  chunk.flags = proto::kCodeFlagOneOfN;
  for (std::size_t i = 0; i < kCode.size(); ++i)
    chunk.masks[i] = static_cast<std::uint8_t>(kCode[i] - '0');
  ASSERT_EQ(request(vc, proto::Command::kSetCode, chunk)[3], 0);
  ASSERT_EQ(request(vc, proto::Command::kSelectCode, proto::SelectCodeRequest{0, {}})[3], 0);
  ASSERT_EQ(request(vc, proto::Command::kSetTiming, proto::SetTimingRequest{100, 0, 0, {}})[3], 0);
  ASSERT_EQ(request(vc, proto::Command::kArm)[3], 0);
}

proto::ExposureEvent next_event(device::VirtualController& vc) {
  auto report = vc.next_event_report();
  EXPECT_TRUE(report.has_value());
  proto::ExposureEvent event{};
  if (report) std::memcpy(&event, report->data() + proto::kHeaderSize, sizeof event);
  return event;
}

SimConveyorOptions small_options() {
  SimConveyorOptions o;
  o.width = 640;
  o.height = 240;
  o.tile_width = 420;
  o.gap = 100;
  o.speed_px_per_s = 10'000;
  return o;
}

TEST(SimCamera, LightsFromTheControllersTransitionsAndFeedsTheEncoder) {
  device::VirtualController vc;
  arm(vc);
  auto camera = make_sim_camera(vc, small_options());
  ASSERT_EQ(camera->open(), "");
  ASSERT_EQ(camera->configure({}), "");
  ASSERT_EQ(camera->start(), "");
  Frame frame;
  std::string error;
  ASSERT_EQ(camera->next_frame(frame, 1000ms, error), FrameWait::kFrame) << error;
  EXPECT_EQ(frame.sequence, 0u);
  EXPECT_EQ(frame.format.pixel_format, PixelFormat::kRgb16);
  EXPECT_EQ(frame.data.size(), 640u * 240u * 6u);
  // The descriptor (ground truth) carries the code the controller actually played.
  const auto descriptor = nlohmann::json::parse(frame.descriptor_json);
  const auto model = imaging::from_descriptor(descriptor);
  ASSERT_TRUE(model.ok()) << model.error();
  ASSERT_EQ(model.value().code.length(), static_cast<int>(kCode.size()));
  for (std::size_t i = 0; i < kCode.size(); ++i)
    EXPECT_EQ(model.value().code.mask(static_cast<int>(i)), kCode[i] - '0') << "slot " << i;
  // 10000 px/s over 52 slots of 100 us: 52 px; the encoder saw 2 counts per px.
  EXPECT_NEAR(model.value().blur_px, 52.0, 0.01);
  const auto event = next_event(vc);
  EXPECT_EQ(event.frame_counter, 1u);
  EXPECT_NEAR(event.encoder_delta, 104, 1);
  // Values are 12-bit DN with a black level of 64.
  const auto dn = frame_to_dn(frame);
  ASSERT_TRUE(dn.ok());
  float lo = 1e9f, hi = -1e9f;
  for (float v : dn.value().channels[1].pixels) {
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  EXPECT_GE(lo, 0.0f);
  EXPECT_LE(hi, 4095.0f);
  EXPECT_GT(hi, 300.0f);  // the belt: 0.35 x 3000 e- at 2.93 e-/DN over 64
}

TEST(SimCamera, LabelsInViewAreTheGroundTruth) {
  device::VirtualController vc;
  arm(vc);
  auto camera = make_sim_camera(vc, small_options());
  ASSERT_EQ(camera->start(), "");
  Frame frame;
  std::string error;
  std::vector<std::string> seen;
  for (int i = 0; i < 12; ++i) {
    ASSERT_EQ(camera->next_frame(frame, 1000ms, error), FrameWait::kFrame) << error;
    for (const auto& t : frame.truth)
      if (seen.empty() || seen.back() != t) seen.push_back(t);
  }
  // 12 frames of 16.7 ms at 10000 px/s: 2000 px of belt, 400 px per label.
  ASSERT_GE(seen.size(), 2u);
  EXPECT_EQ(seen[0], "FS-00000");
  EXPECT_EQ(seen[1], sim_label_scene(1).substr(6));
}

TEST(SimCamera, LostFramesAdvanceTheSequenceAndAreCounted) {
  device::VirtualController vc;
  arm(vc);
  SimConveyorOptions o = small_options();
  o.drop_probability = 0.3;
  o.max_frames = 40;
  o.render_threads = 1;  // exposures then stay one frame ahead of delivery
  auto camera = make_sim_camera(vc, o);
  ASSERT_EQ(camera->start(), "");
  Frame frame;
  std::string error;
  std::uint64_t delivered = 0, gaps = 0, last = 0;
  int events = 0;  // read as they come: the controller keeps only a few unread
  while (camera->next_frame(frame, 1000ms, error) == FrameWait::kFrame) {
    if (delivered > 0) gaps += frame.sequence - last - 1;
    last = frame.sequence;
    ++delivered;
    while (vc.next_event_report()) ++events;
  }
  while (vc.next_event_report()) ++events;
  EXPECT_EQ(camera->counters().frames_delivered, delivered);
  EXPECT_GT(camera->counters().frames_dropped, 0u);
  EXPECT_EQ(camera->counters().frames_delivered + camera->counters().frames_dropped, 40u);
  EXPECT_GT(camera->counters().making_ms, 0.0);  // the host's rendering, timed
  // Every exposure, delivered or lost, has its event.
  EXPECT_EQ(events, 40);
  EXPECT_GE(camera->counters().frames_dropped, gaps);
}

TEST(SimCamera, RefusesBadOptionsNamingThem) {
  SimConveyorOptions o;
  EXPECT_NE(apply_sim_options({{"speed_px_per_s", "fast"}}, o).find("speed_px_per_s"),
            std::string::npos);
  EXPECT_NE(apply_sim_options({{"colour", "red"}}, o).find("colour"), std::string::npos);
  device::VirtualController vc;
  o.jitter = 2;
  EXPECT_NE(make_sim_camera(vc, o)->open().find("jitter"), std::string::npos);
}

/// Standard deviation of the row means of `channel` (DN): print in bands of
/// rows shows there, noise averages out along each row.
double row_means_spread(const imaging::Image& dn, int channel) {
  const imaging::Plane& p = dn.channels[static_cast<std::size_t>(channel)];
  std::vector<double> rows;
  for (int y = 0; y < p.height; ++y) {
    double sum = 0;
    for (int x = 0; x < p.width; ++x) sum += p.at(x, y);
    rows.push_back(sum / p.width);
  }
  double mean = 0, square = 0;
  for (double r : rows) mean += r / rows.size();
  for (double r : rows) square += (r - mean) * (r - mean) / rows.size();
  return std::sqrt(square);
}

TEST(SimCamera, APrintedBeltShowsBandsOfPrintWhereThePlainOneIsFlat) {
  // The first frame: no label has come into view yet, only belt.
  double spread[2] = {0, 0};
  for (const bool print : {false, true}) {
    device::VirtualController vc;
    arm(vc);
    SimConveyorOptions o = small_options();
    ASSERT_EQ(apply_sim_options({{"belt", print ? "print" : "plain"}}, o), "");
    auto camera = make_sim_camera(vc, o);
    ASSERT_EQ(camera->start(), "");
    Frame frame;
    std::string error;
    ASSERT_EQ(camera->next_frame(frame, 1000ms, error), FrameWait::kFrame) << error;
    EXPECT_TRUE(frame.truth.empty());
    const auto dn = frame_to_dn(frame);
    ASSERT_TRUE(dn.ok());
    spread[print] = row_means_spread(dn.value(), 1);
  }
  EXPECT_LT(spread[0], 2.0);  // noise of ~20 DN a pixel, averaged over 640
  EXPECT_GT(spread[1], 5 * spread[0] + 5.0);
  SimConveyorOptions o;
  EXPECT_NE(apply_sim_options({{"belt", "carpet"}}, o).find("belt"), std::string::npos);
}

/// Mean DN of `channel` over the frame's middle (a quarter of the width and height).
double middle_mean(const imaging::Image& dn, int channel) {
  const imaging::Plane& p = dn.channels[static_cast<std::size_t>(channel)];
  double sum = 0;
  int n = 0;
  for (int y = p.height * 3 / 8; y < p.height * 5 / 8; ++y)
    for (int x = p.width * 3 / 8; x < p.width * 5 / 8; ++x, ++n) sum += p.at(x, y);
  return sum / n;
}

TEST(SimCamera, StaticWhiteTargetIsLitByOneLedThroughTheCrosstalk) {
  device::VirtualController vc;
  arm(vc);
  // Code 0 becomes LED 1 alone in every slot (2222...).
  proto::SetCodeRequest chunk{};
  chunk.led_count = 3;
  chunk.total_slots = 52;
  chunk.slot_count = 52;
  chunk.flags = proto::kCodeFlagOneOfN;
  for (int i = 0; i < 52; ++i) chunk.masks[static_cast<std::size_t>(i)] = 2;
  ASSERT_EQ(request(vc, proto::Command::kDisarm)[3], 0);
  ASSERT_EQ(request(vc, proto::Command::kSetCode, chunk)[3], 0);
  ASSERT_EQ(request(vc, proto::Command::kArm)[3], 0);
  SimConveyorOptions o;
  ASSERT_EQ(apply_sim_options({{"width", "128"},
                               {"height", "96"},
                               {"target", "white:0.8"},
                               {"crosstalk", "0.9,0.1,0,0.1,0.8,0.1,0,0.1,0.9"},
                               {"black_level", "100"},
                               {"full_well", "9000"},
                               {"bit_depth", "12"}},
                              o),
            "");
  auto camera = make_sim_camera(vc, o);
  ASSERT_EQ(camera->open(), "");
  ASSERT_EQ(camera->start(), "");
  Frame frame;
  std::string error;
  ASSERT_EQ(camera->next_frame(frame, 1000ms, error), FrameWait::kFrame) << error;
  EXPECT_TRUE(frame.truth_in_view.empty());
  const auto dn = frame_to_dn(frame);
  ASSERT_TRUE(dn.ok()) << dn.error();
  // LED 1 gives each channel crosstalk[c][1] x 3000 e- x 0.8 over the black level.
  const double gain = sim_truth(o).gain_e_per_dn;
  EXPECT_NEAR(gain, 9000.0 / 4095.0, 1e-12);
  const double column[3] = {0.1, 0.8, 0.1};
  for (int c = 0; c < 3; ++c)
    EXPECT_NEAR(middle_mean(dn.value(), c), 100 + column[c] * 3000 * 0.8 / gain, 2.0) << c;
  // The belt stands still: no encoder counts.
  EXPECT_EQ(next_event(vc).encoder_delta, 0);
  // Disarmed: dark frames at the black level.
  ASSERT_EQ(request(vc, proto::Command::kDisarm)[3], 0);
  ASSERT_EQ(camera->next_frame(frame, 1000ms, error), FrameWait::kFrame) << error;  // in flight
  ASSERT_EQ(camera->next_frame(frame, 1000ms, error), FrameWait::kFrame) << error;
  ASSERT_EQ(camera->next_frame(frame, 1000ms, error), FrameWait::kFrame) << error;
  const auto dark = frame_to_dn(frame);
  ASSERT_TRUE(dark.ok());
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(middle_mean(dark.value(), c), 100, 0.2) << c;
}

TEST(SimCamera, FalloffDimsTheCornersOfTheStaticTarget) {
  device::VirtualController vc;
  arm(vc);
  SimConveyorOptions o;
  ASSERT_EQ(apply_sim_options({{"width", "200"},
                               {"height", "100"},
                               {"target", "white"},
                               {"falloff", "0.3"},
                               {"read_noise", "0"}},
                              o),
            "");
  auto camera = make_sim_camera(vc, o);
  ASSERT_EQ(camera->start(), "");
  Frame frame;
  std::string error;
  ASSERT_EQ(camera->next_frame(frame, 1000ms, error), FrameWait::kFrame) << error;
  const auto dn = frame_to_dn(frame);
  ASSERT_TRUE(dn.ok());
  const imaging::Plane& g = dn.value().channels[1];
  double corner = 0, centre = 0;
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 4; ++x) {
      corner += g.at(x, y) - 64;
      centre += g.at(98 + x, 48 + y) - 64;
    }
  EXPECT_NEAR(corner / centre, 0.7, 0.05);
}

TEST(SimCamera, RefusesBadTargetAndCalibrationOptions) {
  SimConveyorOptions o;
  EXPECT_NE(apply_sim_options({{"target", "grey"}}, o).find("target"), std::string::npos);
  EXPECT_NE(apply_sim_options({{"target", "white:1.5"}}, o).find("white:1.5"), std::string::npos);
  EXPECT_NE(apply_sim_options({{"crosstalk", "1,0,0"}}, o).find("crosstalk"), std::string::npos);
  EXPECT_NE(apply_sim_options({{"crosstalk", "1,0,0,0,1,0,0,x,1"}}, o).find("crosstalk"),
            std::string::npos);
  device::VirtualController vc;
  SimConveyorOptions labels;
  labels.falloff = 0.2;
  EXPECT_NE(make_sim_camera(vc, labels)->open().find("falloff"), std::string::npos);
  SimConveyorOptions deep;
  deep.bit_depth = 20;
  EXPECT_NE(make_sim_camera(vc, deep)->open().find("bit_depth"), std::string::npos);
  EXPECT_DOUBLE_EQ(sim_truth(SimConveyorOptions{}).px_per_count, 0.5);
}

}  // namespace
}  // namespace flutterscan::capture
