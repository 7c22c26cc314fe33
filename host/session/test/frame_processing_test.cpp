// A worker's work on one frame: a sim frame with a whole label in view is
// deblurred and its label read at its ground truth; a frame whose event does
// not fit the code is refused, logged, not processed.
#include "session/frame_processing.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <functional>
#include <iostream>
#include <optional>
#include <random>
#include <set>

#include "capture/sim_camera.hpp"
#include "device/controller_client.hpp"
#include "device/in_process_transport.hpp"
#include "device/virtual_controller.hpp"
#include "imaging/bar_sums.hpp"
#include "imaging/capture_descriptor.hpp"
#include "session/session_clock.hpp"
#include "session/window_tries.hpp"
#include "sim/scene.hpp"

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

/// The first `count` frames of a sim belt 640x240 (labels 100 px apart), each
/// with the event that lit it (the encoder's counts from the frame's own
/// descriptor) and the belt's travel, at the light of config.optics.electrons: those `keep` takes
/// (given the frame and its number from 0), at most `max_kept`.
std::vector<FrameJob> belt_frames(const SessionConfig& config, int count,
                                  const std::function<bool(const capture::Frame&, int)>& keep,
                                  std::size_t max_kept) {
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
  belt.electrons = config.optics.electrons;
  auto camera = capture::make_sim_camera(*controller, belt);
  EXPECT_EQ(camera->start(), "");
  std::vector<FrameJob> jobs;
  std::string error;
  for (int i = 0; i < count && jobs.size() < max_kept; ++i) {
    FrameJob job;
    camera->next_frame(job.frame, std::chrono::milliseconds(1000), error);
    if (!keep(job.frame, i)) continue;
    const auto model = imaging::from_descriptor(nlohmann::json::parse(job.frame.descriptor_json));
    EXPECT_TRUE(model.ok());
    job.index = static_cast<std::uint64_t>(i);
    job.travel_px = i * belt.speed_px_per_s * belt.frame_period_us * 1e-6;
    job.event.frame_counter = static_cast<std::uint32_t>(i + 1);
    job.event.slot_count = static_cast<std::uint16_t>(config.controller.parsed_code.length());
    job.event.slot_time_us = config.controller.slot_time_us;
    job.event.encoder_delta =
        static_cast<std::int32_t>(std::lround(model.value().blur_px / config.optics.px_per_count));
    jobs.push_back(std::move(job));
  }
  return jobs;
}

/// A sim frame with a whole label in view (belt_frames), the `skip`-th such
/// frame, as the 8th frame of a session at 123 px of travel.
FrameJob job_with_a_label(const SessionConfig& config, int skip = 0) {
  int found = 0;
  std::vector<FrameJob> jobs = belt_frames(
      config, 80,
      [&](const capture::Frame& f, int i) { return i >= 4 && !f.truth.empty() && found++ == skip; },
      1);
  EXPECT_FALSE(jobs.empty());
  FrameJob job = jobs.empty() ? FrameJob{} : std::move(jobs.front());
  job.index = 7;
  job.travel_px = 123;
  job.event.frame_counter = 8;
  return job;
}

TEST(FrameProcessing, AWholeLabelIsDeblurredAndReadAtItsGroundTruth) {
  const SessionConfig config = small_config();
  FrameJob job = job_with_a_label(config);
  ASSERT_FALSE(job.frame.truth.empty());
  const std::vector<std::string> truth = job.frame.truth;
  const std::uint64_t sequence = job.frame.sequence;
  WorkerShared shared(config);
  const FrameOutcome out = process_frame(job, config, shared, nullptr);
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
  // Each code says the view it was read on: white paper, black ink, nominal light: the first.
  ASSERT_FALSE(out.log["decoded"].empty()) << out.log.dump();
  for (const auto& code : out.log["decoded"]) {
    EXPECT_EQ(code["view"], "linear") << code.dump();
    EXPECT_EQ(code["decoder"], "zxing") << code.dump();
  }
  for (const char* stage : {"convert", "deblur", "decode"})
    EXPECT_TRUE(out.log["times_ms"].contains(stage)) << stage;
  EXPECT_EQ(out.log["event"]["counter"], 8);
  EXPECT_EQ(out.descriptor["capture"]["sequence"], sequence);
  EXPECT_EQ(out.latent.width, 640);
  EXPECT_FALSE(out.frame.data.empty());  // kept for the results stage to save
}

// A frame refined on time leaves its refined / encoder ratio for the workers;
// a frame taken with half the queue waiting behind it skips the refinement and
// uses that ratio (flagged), unless processing.refine_when_behind.
TEST(FrameProcessing, AFrameTakenBehindUsesTheLatestRefinedRatioInsteadOfRefining) {
  SessionConfig config = small_config();
  ASSERT_EQ(config.processing.queue_depth, 4u);
  EXPECT_FALSE(behind_queue(1, 4));
  EXPECT_TRUE(behind_queue(2, 4));
  EXPECT_TRUE(behind_queue(1, 1));
  EXPECT_FALSE(behind_queue(0, 0));
  const FrameJob original = job_with_a_label(config);
  WorkerShared shared(config);
  FrameJob first_behind = original;  // before any frame was refined: the encoder's blur
  first_behind.waiting_behind = 3;
  const FrameOutcome unrefined = process_frame(first_behind, config, shared, nullptr);
  ASSERT_TRUE(unrefined.processed) << unrefined.log.dump();
  EXPECT_EQ(unrefined.log["motion"]["reused_ratio"].get<double>(), 1.0);
  EXPECT_EQ(shared.motion_ratio.load(), 0.0);
  FrameJob on_time = original;
  const FrameOutcome refined = process_frame(on_time, config, shared, nullptr);
  ASSERT_TRUE(refined.processed) << refined.log.dump();
  ASSERT_TRUE(refined.log["motion"]["used"].get<bool>()) << refined.log["motion"].dump();
  const double ratio = refined.log["motion"]["refined_blur_px"].get<double>() /
                       refined.log["motion"]["encoder_blur_px"].get<double>();
  EXPECT_NEAR(shared.motion_ratio.load(), ratio, 1e-4);

  shared.motion_ratio.store(1.01);  // as a line whose encoder reads 1% short
  FrameJob behind = original;
  behind.waiting_behind = 2;
  const FrameOutcome reused = process_frame(behind, config, shared, nullptr);
  ASSERT_TRUE(reused.processed) << reused.log.dump();
  const auto flags = reused.log["flags"];
  EXPECT_NE(std::find(flags.begin(), flags.end(), "motion-reused"), flags.end()) << flags.dump();
  EXPECT_EQ(reused.log["motion"]["reused_ratio"].get<double>(), 1.01);
  EXPECT_NEAR(reused.log["model"]["blur_px"].get<double>(),
              1.01 * reused.log["motion"]["encoder_blur_px"].get<double>(), 0.01);
  EXPECT_FALSE(reused.decode_failed) << reused.log.dump();

  config.processing.refine_when_behind = true;
  FrameJob behind_refined = original;
  behind_refined.waiting_behind = 2;
  const FrameOutcome kept = process_frame(behind_refined, config, shared, nullptr);
  ASSERT_TRUE(kept.processed);
  EXPECT_TRUE(kept.log["motion"].contains("refined_blur_px")) << kept.log["motion"].dump();
}

/// `job`'s frame as if its whole scene reflected `share[c]` of the light in
/// channel c: every sample's signal above the black level scaled (the sim's RGB
/// 16-bit frames).
void tint_scene(FrameJob& job, std::array<double, 3> share) {
  ASSERT_EQ(job.frame.format.pixel_format, capture::PixelFormat::kRgb16);
  const auto model = imaging::from_descriptor(nlohmann::json::parse(job.frame.descriptor_json));
  ASSERT_TRUE(model.ok());
  const double black = model.value().black_level;
  for (std::size_t i = 0; i + 1 < job.frame.data.size(); i += 2) {
    const double v = job.frame.data[i] | (job.frame.data[i + 1] << 8);
    const double k = share[(i / 2) % 3];
    const auto scaled = static_cast<std::uint16_t>(std::lround(black + (v - black) * k));
    job.frame.data[i] = static_cast<std::uint8_t>(scaled & 0xff);
    job.frame.data[i + 1] = static_cast<std::uint8_t>(scaled >> 8);
  }
}

TEST(FrameProcessing, ACodeOnPaperDimmerThanWhiteIsFoundByItsPrintAndRead) {
  const SessionConfig config = small_config();
  FrameJob job = job_with_a_label(config);
  ASSERT_FALSE(job.frame.truth.empty());
  const std::vector<std::string> truth = job.frame.truth;
  tint_scene(job, {0.5, 0.5, 0.5});  // label paper about 0.45: below the paper finder's 0.62
  WorkerShared shared(config);
  const FrameOutcome out = process_frame(job, config, shared, nullptr);
  ASSERT_TRUE(out.processed) << out.log.dump();
  EXPECT_GE(out.log["decode_windows"].get<int>(), 1) << out.log.dump();
  for (const auto& value : truth)
    EXPECT_TRUE(std::any_of(out.sightings.begin(), out.sightings.end(),
                            [&](const Sighting& s) { return s.decoded && s.value == value; }))
        << value << " not read on dim paper: " << out.log.dump();
}

TEST(FrameProcessing, AnEventThatDoesNotFitTheCodeIsLoggedNotProcessed) {
  const SessionConfig config = small_config();
  FrameJob job = job_with_a_label(config);
  job.event.slot_count = static_cast<std::uint16_t>(job.event.slot_count + 1);
  WorkerShared shared(config);
  const FrameOutcome out = process_frame(job, config, shared, nullptr);
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
    WorkerShared shared(config);
    const FrameOutcome out = process_frame(job, config, shared, nullptr);
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

/// A frame whose label joint Wiener alone does not read, at the first light of
/// 400, 300, 250 or 200 e- where one misses (the first frames with a whole label
/// searched; the reader's second, sRGB-encoded view reads more than it did at
/// 400-300 e-), with config.optics.electrons set to its light; none if every label read.
std::optional<FrameJob> frame_joint_wiener_misses(SessionConfig& config) {
  for (const double electrons : {400.0, 300.0, 250.0, 200.0}) {
    SessionConfig plain = config;
    plain.optics.electrons = electrons;
    plain.processing.cascade = false;
    for (int skip = 0; skip < 6; ++skip) {
      FrameJob job = job_with_a_label(plain, skip);
      FrameJob copy = job;
      WorkerShared shared(plain);
      const FrameOutcome out = process_frame(copy, plain, shared, nullptr);
      if (out.processed && out.decode_failed) {
        config.optics.electrons = electrons;
        return job;
      }
    }
  }
  return std::nullopt;
}

TEST(FrameProcessing, TheCascadeReadsAWindowJointWienerMissedByDeblurringItAgainWithTv) {
  SessionConfig config = small_config();
  std::optional<FrameJob> missed = frame_joint_wiener_misses(config);
  ASSERT_TRUE(missed) << "joint Wiener read every label at 400 to 200 e-";
  const std::vector<std::string> truth = missed->frame.truth;
  config.processing.cascade = true;
  config.processing.second_pass_ms = kMaxSecondPassMs;  // offline: every window
  ASSERT_EQ(check_config(config), "");
  FrameJob job = *missed;
  WorkerShared shared(config);
  const FrameOutcome out = process_frame(job, config, shared, nullptr);
  ASSERT_TRUE(out.processed) << out.log.dump();
  const nlohmann::json& pass = out.log["second_pass"];
  ASSERT_GE(pass["windows"].size(), 1u) << out.log.dump();
  EXPECT_GT(pass["windows"][0]["ms"].get<double>(), 0);
  EXPECT_EQ(pass["skipped"], 0);
  EXPECT_TRUE(out.log["times_ms"].contains("second_pass"));
  for (const auto& value : truth)
    EXPECT_TRUE(std::any_of(out.sightings.begin(), out.sightings.end(),
                            [&](const Sighting& s) { return s.decoded && s.value == value; }))
        << value << " not read by the second pass: " << out.log.dump();
  EXPECT_FALSE(out.decode_failed);
  EXPECT_EQ(pass["windows"][0]["read"], nlohmann::json(truth)) << pass.dump();

  // The same frame turned to -x: the window is pasted into the camera's latent too.
  SessionConfig mirrored = config;
  mirrored.optics.direction = "-x";
  ASSERT_EQ(check_config(mirrored), "");
  FrameJob turned = *missed;
  const int w = turned.frame.format.width;
  const std::size_t stride = turned.frame.format.row_bytes != 0 ? turned.frame.format.row_bytes
                                                                : static_cast<std::size_t>(w) * 6;
  for (int y = 0; y < turned.frame.format.height; ++y)
    for (int x = 0; x < w / 2; ++x)
      std::swap_ranges(
          turned.frame.data.begin() + static_cast<std::ptrdiff_t>(y * stride + x * 6),
          turned.frame.data.begin() + static_cast<std::ptrdiff_t>(y * stride + x * 6 + 6),
          turned.frame.data.begin() + static_cast<std::ptrdiff_t>(y * stride + (w - 1 - x) * 6));
  WorkerShared shared_turned(mirrored);
  const FrameOutcome out_turned = process_frame(turned, mirrored, shared_turned, nullptr);
  ASSERT_TRUE(out_turned.processed) << out_turned.log.dump();
  EXPECT_FALSE(out_turned.decode_failed) << out_turned.log.dump();
  ASSERT_EQ(out_turned.sightings.size(), out.sightings.size());
}

TEST(FrameProcessing, InDimLightTheBarSumsReadALinearCodeTvMisses) {
  // Dim frames until one where a window's tv latent reads no linear code and
  // the rows summed along its bars do (they are tried only where tv read none;
  // at 640x240 the first is at 110 e-, the sim's second label frame).
  SessionConfig config = small_config();
  config.processing.second_pass_ms = kMaxSecondPassMs;  // offline: every window
  for (const double electrons : {110.0, 80.0, 150.0, 200.0}) {
    config.optics.electrons = electrons;
    ASSERT_EQ(check_config(config), "");
    for (int skip = 0; skip < 4; ++skip) {
      FrameJob job = job_with_a_label(config, skip);
      const std::vector<std::string> truth = job.frame.truth;
      WorkerShared shared(config);
      const FrameOutcome out = process_frame(job, config, shared, nullptr);
      ASSERT_TRUE(out.processed) << out.log.dump();
      if (!out.log.contains("second_pass") || !out.log["second_pass"].contains("windows")) continue;
      for (const auto& window : out.log["second_pass"]["windows"]) {
        if (!window.contains("bar_sums") || window["bar_sums"]["read"].empty()) continue;
        for (const auto& value : window["bar_sums"]["read"]) {
          EXPECT_NE(std::find(truth.begin(), truth.end(), value.get<std::string>()), truth.end())
              << value << " is no label's value: " << window.dump();
          EXPECT_TRUE(std::any_of(out.sightings.begin(), out.sightings.end(),
                                  [&](const Sighting& s) { return s.decoded && s.value == value; }))
              << out.log.dump();
        }
        EXPECT_LE(std::abs(window["bar_sums"]["slope"].get<double>()), imaging::kMaxBarSlope);
        return;
      }
    }
  }
  FAIL() << "the bar sums read no label tv missed at 80 to 200 e-";
}

TEST(FrameProcessing, AColourPrintFrameDeblurredPerChannelGetsTheSecondPassToo) {
  SessionConfig config = small_config();
  std::optional<FrameJob> missed = frame_joint_wiener_misses(config);
  ASSERT_TRUE(missed);
  config.processing.second_pass_ms = kMaxSecondPassMs;  // offline: every window
  ASSERT_EQ(check_config(config), "");
  FrameJob job = *missed;
  tint_scene(job, {1.0, 0.55, 0.3});  // a warm card: the channels disagree with one grey latent
  WorkerShared shared(config);
  const FrameOutcome out = process_frame(job, config, shared, nullptr);
  ASSERT_TRUE(out.processed) << out.log.dump();
  ASSERT_NE(out.log["model"]["chosen"].get<std::string>().find("per-channel"), std::string::npos)
      << out.log["model"].dump();
  const nlohmann::json& pass = out.log["second_pass"];
  EXPECT_FALSE(pass.contains("not_run")) << pass.dump();
  EXPECT_GE(pass["windows"].size(), 1u) << out.log.dump();
}

TEST(FrameProcessing, AWindowTheBudgetCannotPayForIsFlaggedAndStaysANoRead) {
  SessionConfig config = small_config();
  std::optional<FrameJob> missed = frame_joint_wiener_misses(config);
  ASSERT_TRUE(missed);
  config.processing.second_pass_ms = 0;
  ASSERT_EQ(check_config(config), "");
  WorkerShared shared(config);
  const FrameOutcome out = process_frame(*missed, config, shared, nullptr);
  ASSERT_TRUE(out.processed);
  EXPECT_TRUE(out.decode_failed);
  EXPECT_GE(out.log["second_pass"]["skipped"].get<int>(), 1) << out.log.dump();
  EXPECT_TRUE(out.log["second_pass"]["windows"].empty());
  const auto& flags = out.log["flags"];
  EXPECT_NE(std::find(flags.begin(), flags.end(), "second-pass-budget"), flags.end())
      << flags.dump();
}

TEST(FrameProcessing, WorkThatWouldEndPastTheFramesDeadlineIsNotStartedAndIsNamed) {
  SessionConfig config = small_config();
  std::optional<FrameJob> missed = frame_joint_wiener_misses(config);
  ASSERT_TRUE(missed);
  config.processing.second_pass_ms = kMaxSecondPassMs;  // the credit pays for every window
  config.processing.latency_ms = 1e5;                   // the result is due 100 s after arrival
  ASSERT_EQ(check_config(config), "");
  WorkerShared shared(config);
  // A window of tv has lately cost 1,000 s a megapixel: none ends by then.
  shared.second_pass.settle(0, 5e9, 1'000'000);
  FrameJob job = *missed;
  job.frame.host_arrival_ns = now_ns();
  const FrameOutcome out = process_frame(job, config, shared, nullptr);
  ASSERT_TRUE(out.processed);
  EXPECT_TRUE(out.decode_failed);
  EXPECT_GE(out.log["second_pass"]["past_deadline"].get<int>(), 1) << out.log.dump();
  EXPECT_TRUE(out.log["second_pass"]["windows"].empty());
  const auto& flags = out.log["flags"];
  EXPECT_NE(std::find(flags.begin(), flags.end(), "deadline"), flags.end()) << flags.dump();
  // Due a second after arrival, the same frame's window is deblurred again and read.
  config.processing.latency_ms = 1000;
  WorkerShared roomy(config);
  FrameJob again = *missed;
  again.frame.host_arrival_ns = now_ns();
  const FrameOutcome read = process_frame(again, config, roomy, nullptr);
  EXPECT_FALSE(read.log["second_pass"].contains("past_deadline")) << read.log.dump();
  EXPECT_FALSE(read.log["second_pass"]["windows"].empty());
}

TEST(FrameProcessing, TheAutoDecodeBudgetIsWhatTheFramesShareLeavesAndEndsByItsDeadline) {
  SessionConfig config = small_config();
  config.processing.latency_ms = -1;  // "auto": workers + 1 frame periods
  ASSERT_EQ(check_config(config), "");
  const std::vector<FrameJob> jobs = belt_frames(
      config, 40, [](const capture::Frame& f, int i) { return i >= 4 && !f.truth.empty(); }, 1);
  ASSERT_FALSE(jobs.empty());
  // 30 fps on the config's workers: the share is 2 x 33.3 ms x kShare.
  WorkerShared shared(config);
  shared.second_pass.expect_period_ms(1000 / 30.0);
  shared.live_arrivals = true;  // frames arriving as exposed: deadlines from their arrival
  const double share = shared.second_pass.frame_share_ms();
  FrameJob job = jobs[0];
  job.frame.host_arrival_ns = now_ns();
  const FrameOutcome out = process_frame(job, config, shared, nullptr);
  ASSERT_TRUE(out.processed) << out.log.dump();
  const double before_decode =
      out.log["times_ms"]["convert"].get<double>() + out.log["times_ms"]["deblur"].get<double>();
  const double budget = out.log["decode_budget_ms"].get<double>();
  EXPECT_LE(budget, share - before_decode + 0.1) << out.log.dump();
  EXPECT_GE(budget, 1.0);
  // A frame that waited until a ms before its deadline (workers + 1 periods)
  // gets the first window's minimum, and the deadline does not hold even that:
  // every window is left for a frame after, none judged.
  FrameJob late = jobs[0];
  const double due_ms = (config.processing.workers + 1) * 1000 / 30.0;
  late.frame.host_arrival_ns = now_ns() - static_cast<std::int64_t>((due_ms - 1) * 1e6);
  const FrameOutcome rushed = process_frame(late, config, shared, nullptr);
  EXPECT_EQ(rushed.log["decode_budget_ms"].get<double>(), 1.0) << rushed.log.dump();
  EXPECT_GE(rushed.log.value("decode_windows", 0), 1);
  EXPECT_EQ(rushed.log.value("decode_left", 0), rushed.log.value("decode_windows", 0));
  EXPECT_TRUE(rushed.sightings.empty());
}

// A label coming into view upstream: its code region reaches into the columns
// the latent has no support in (within a blur of the upstream edge), on paper
// that reaches into them too. The second pass leaves it for a later frame,
// logged as entering, as it leaves a code going out of view downstream, and
// every label reads once whole in view.
TEST(SecondPass, CodesComingIntoOrGoingOutOfViewAreLeftForAnotherFrame) {
  SessionConfig config = small_config();
  config.processing.cascade = true;
  config.processing.second_pass_ms = kMaxSecondPassMs;  // offline: every window it takes
  ASSERT_EQ(check_config(config), "");
  std::vector<FrameJob> jobs = belt_frames(
      config, 24, [](const capture::Frame&, int) { return true; }, 24);
  int entering = 0, retried = 0;
  std::set<std::string> whole, read;
  WorkerShared shared(config);
  for (FrameJob& job : jobs) {
    whole.insert(job.frame.truth.begin(), job.frame.truth.end());
    const FrameOutcome out = process_frame(job, config, shared, nullptr);
    ASSERT_TRUE(out.processed) << out.log.dump();
    entering += out.log.value("/second_pass/entering"_json_pointer, 0);
    // Nor is a code leaving the view downstream (whole in an earlier frame) deblurred again.
    if (out.log.contains("second_pass") && out.log["second_pass"].contains("windows"))
      for (const auto& w : out.log["second_pass"]["windows"]) {
        ++retried;
        EXPECT_LT(w["x"].get<int>() + w["width"].get<int>(), job.frame.format.width) << w.dump();
      }
    for (const Sighting& s : out.sightings)
      if (s.decoded) read.insert(s.value);
  }
  EXPECT_GE(entering, 1) << "no label came into view in " << jobs.size() << " frames";
  std::cout << entering << " code region(s) left as they came into view, " << retried
            << " window(s) deblurred again\n";
  ASSERT_FALSE(whole.empty());
  for (const std::string& value : whole) EXPECT_EQ(read.count(value), 1u) << value;
}

// Each try runs as its own unit, in the order docs/algorithms.md gives, each
// charged before it runs and logged with what it cost and read; a try switched
// off does not run. A label in light too dim for anything to read: every try
// switched on runs in its window.
TEST(SecondPass, EachTryRunsInItsOrderChargedAndLoggedAndOnlyWhereSwitchedOn) {
  SessionConfig config = small_config();
  config.optics.electrons = 15;
  config.processing.cascade = true;
  config.processing.second_pass_ms = kMaxSecondPassMs;  // offline: every window
  std::string problem;
  config.processing.second_pass_tries = *parse_second_pass_tries("all", problem);
  ASSERT_EQ(check_config(config), "");
  const FrameJob dim = job_with_a_label(config);
  auto tries_run = [&](const SessionConfig& c) {
    FrameJob job = dim;
    WorkerShared shared(c);
    const FrameOutcome out = process_frame(job, c, shared, nullptr);
    EXPECT_TRUE(out.processed) << out.log.dump();
    std::vector<std::vector<std::string>> names;
    for (const auto& window : out.log["second_pass"]["windows"]) {
      EXPECT_TRUE(window["read"].empty()) << "a code read at 15 e-: " << window.dump();
      names.emplace_back();
      for (const auto& t : window["tries"]) {
        names.back().push_back(t["name"]);
        EXPECT_GE(t["ms"].get<double>(), 0) << t.dump();
        EXPECT_EQ(t["estimate_ms"].get<double>() > 0, t["name"] != "bar-sums") << t.dump();
      }
    }
    return names;
  };
  const auto all = tries_run(config);
  ASSERT_FALSE(all.empty());
  for (const std::vector<std::string>& window : all) {
    // tv; bar-sums once; tv-on-sums and fit once per count of rows summed
    // (one or two); isotropic-tv at each of its two weights.
    ASSERT_GE(window.size(), 6u);
    EXPECT_EQ(window[0], "tv");
    EXPECT_EQ(window[1], "bar-sums");
    const auto n = static_cast<std::ptrdiff_t>((window.size() - 4) / 2);
    ASSERT_EQ(window.size(), static_cast<std::size_t>(4 + 2 * n));
    EXPECT_TRUE(std::all_of(window.begin() + 2, window.begin() + 2 + n,
                            [](const std::string& t) { return t == "tv-on-sums"; }));
    EXPECT_TRUE(std::all_of(window.begin() + 2 + n, window.begin() + 2 + 2 * n,
                            [](const std::string& t) { return t == "fit"; }));
    EXPECT_EQ(window[window.size() - 2], "isotropic-tv");
    EXPECT_EQ(window.back(), "isotropic-tv");
  }
  config.processing.second_pass_tries = *parse_second_pass_tries("bar-sums", problem);
  for (const std::vector<std::string>& window : tries_run(config))
    EXPECT_EQ(window, (std::vector<std::string>{"tv", "bar-sums"}));
}

// The decode's budget: a frame whose windows outlast it decodes some, counts
// and flags the rest and judges none of them (no NO-READ for a label not
// decoded); the next frame over the same belt reads those first, so the two
// frames read all that one unbounded frame reads.
TEST(FrameProcessing, WindowsOverTheDecodeBudgetAreLeftFlaggedUnjudgedAndReadNext) {
  SessionConfig config = small_config();
  config.processing.second_pass_ms = 0;  // the first pass alone
  ASSERT_EQ(check_config(config), "");
  // A frame with two windows or more, read whole.
  std::optional<FrameJob> busy;
  std::set<std::string> unbounded;
  for (const FrameJob& job : belt_frames(
           config, 40, [](const capture::Frame&f, int i) { return i >= 4 && !f.truth.empty(); },
           12)) {
    FrameJob copy = job;
    WorkerShared shared(config);
    const FrameOutcome out = process_frame(copy, config, shared, nullptr);
    if (out.log.value("decode_windows", 0) < 2) continue;
    for (const Sighting& s : out.sightings)
      if (s.decoded) unbounded.insert(s.value);
    EXPECT_FALSE(out.log.contains("decode_left")) << out.log.dump();
    busy = job;
    break;
  }
  ASSERT_TRUE(busy) << "no sim frame with two windows";
  ASSERT_FALSE(unbounded.empty());
  config.processing.decode_ms = 1e-3;  // the first window's first view only
  ASSERT_EQ(check_config(config), "");
  WorkerShared shared(config);
  std::set<std::string> read;
  int left = 0;
  for (int frame = 0; frame < 2; ++frame) {
    FrameJob job = *busy;
    const FrameOutcome out = process_frame(job, config, shared, nullptr);
    ASSERT_TRUE(out.processed) << out.log.dump();
    for (const Sighting& s : out.sightings)
      if (s.decoded) read.insert(s.value);
    if (frame == 0) {
      left = out.log.value("decode_left", 0);
      ASSERT_GE(left, 1) << out.log.dump();
      EXPECT_LT(left, out.log["decode_windows"].get<int>());
      EXPECT_NE(std::find(out.log["flags"].begin(), out.log["flags"].end(), "decode-budget"),
                out.log["flags"].end());
      // Only the windows decoded are judged.
      EXPECT_LE(out.sightings.size(),
                out.log["decode_windows"].get<std::size_t>() - static_cast<std::size_t>(left));
    }
  }
  for (const std::string& value : unbounded)
    EXPECT_TRUE(read.contains(value)) << value << " not read in two bounded frames";
}

TEST(SecondPassTries, NamedOneByOneNoneOrAllAndEachNeedsWhatItWorksOn) {
  std::string problem;
  const auto defaults = parse_second_pass_tries(kDefaultSecondPassTries, problem);
  ASSERT_TRUE(defaults) << problem;
  EXPECT_EQ(*defaults, SecondPassTries{});
  EXPECT_EQ(second_pass_tries_name(SecondPassTries{}), kDefaultSecondPassTries);
  const auto all = parse_second_pass_tries("all", problem);
  ASSERT_TRUE(all);
  EXPECT_EQ(second_pass_tries_name(*all), "bar-sums,tv-on-sums,fit,isotropic-tv");
  const auto none = parse_second_pass_tries(" none ", problem);
  ASSERT_TRUE(none);
  EXPECT_EQ(second_pass_tries_name(*none), "none");
  const auto two = parse_second_pass_tries("isotropic-tv, bar-sums", problem);
  ASSERT_TRUE(two);
  EXPECT_TRUE(two->bar_sums && two->isotropic_tv && !two->fit && !two->tv_on_sums);
  EXPECT_FALSE(parse_second_pass_tries("fit", problem));
  EXPECT_NE(problem.find("needs bar-sums"), std::string::npos) << problem;
  EXPECT_FALSE(parse_second_pass_tries("bar-sums,tv", problem));
  EXPECT_NE(problem.find("'tv' is not a second-pass try"), std::string::npos) << problem;
}

TEST(SecondPass, RetriesEveryUnreadLabelAndTheCodeRegionsOffThem) {
  const reader::LabelRegion label{100, 300, false, 0, 0};       // rows not measured: every row
  const reader::LabelRegion on_label{150, 250, false, 10, 50};  // inside the label: not again
  const reader::LabelRegion carton{400, 520, false, 20, 90};    // a code printed on a carton
  const reader::LabelRegion below{120, 200, false, 300, 340};
  const reader::LabelRegion measured{100, 300, false, 0, 200};  // a label whose rows are known
  const std::vector<reader::LabelRegion> paper{label}, code{on_label, carton};
  const auto retried = retry_regions(paper, code);
  ASSERT_EQ(retried.size(), 2u);
  EXPECT_EQ(retried[0].begin, 100);
  EXPECT_EQ(retried[1].begin, 400);
  // Across the motion too: a region below a label whose rows are known is retried on its own.
  const std::vector<reader::LabelRegion> measured_paper{measured}, code_below{below};
  EXPECT_EQ(retry_regions(measured_paper, code_below).size(), 2u);
  EXPECT_EQ(retry_regions({}, code).size(), 2u);
  EXPECT_TRUE(retry_regions({}, {}).empty());
}

// A code read covers a box on the belt: a window over part of it (a label
// leaving the view, its code's centre gone past the edge) was read already; a
// window beside it along the motion, or above or below it, was not.
TEST(SecondPass, TvsBarSumsReadsCountOnlyWhereJointWienersSumsSupportEveryCharacter) {
  auto spec = sim::parse_scene("ean13:590123412345");
  ASSERT_TRUE(spec.ok());
  spec.value().width = 480;
  spec.value().height = 240;
  spec.value().module_px = 2.5;
  spec.value().print_blur_px = 1.0;
  auto sharp = sim::render_scene(spec.value());
  ASSERT_TRUE(sharp.ok()) << sharp.error();
  const reader::BarcodeReadout readout = reader::read_barcodes(sharp.value());
  ASSERT_EQ(readout.codes.size(), 1u);
  // The sums: the label through noise (a tenth of the bars' contrast, rms).
  imaging::Plane sums = sharp.value();
  std::mt19937_64 rng(3);
  std::normal_distribution<float> noise(0.0f, 0.08f);
  for (float& v : sums.pixels) v += noise(rng);
  const reader::DecodedCode read = readout.codes.front();
  reader::DecodedCode misread = read;  // 5901234123457 with its fifth digit 2 -> 9: valid too
  misread.text = "5901934123450";
  reader::DecodedCode code128 = read;
  code128.format = "Code128";
  std::vector<BarSumsTry::Checked> checked;
  const std::vector<reader::DecodedCode> kept =
      supported_reads(sums, {read, misread, code128}, checked);
  ASSERT_EQ(kept.size(), 1u);
  EXPECT_EQ(kept.front().text, read.text);
  ASSERT_EQ(checked.size(), 3u);
  EXPECT_TRUE(checked[0].kept);
  EXPECT_GE(checked[0].margin, 1.0);
  EXPECT_FALSE(checked[1].kept);
  EXPECT_LT(checked[1].margin, 0.0);
  EXPECT_FALSE(checked[2].kept);
  EXPECT_NE(checked[2].problem.find("Code128"), std::string::npos) << checked[2].problem;
}

TEST(BeltReads, ACodeReadCoversItsWholeBoxOnTheBelt) {
  reader::DecodedCode code;
  code.quality.corners = {{{600, 100}, {800, 100}, {800, 160}, {600, 160}}};
  const BeltBox box = belt_box(code, imaging::Direction::kPlusX, 1000, 400, 250);
  EXPECT_DOUBLE_EQ(box.begin, 600 - 250);
  EXPECT_DOUBLE_EQ(box.end, 800 - 250);
  EXPECT_DOUBLE_EQ(box.across_begin, 100);
  EXPECT_DOUBLE_EQ(box.across_end, 160);
  // Moving -y the rows run along the motion, from the bottom; the columns across it.
  const BeltBox turned = belt_box(code, imaging::Direction::kMinusY, 1000, 400, 0);
  EXPECT_DOUBLE_EQ(turned.begin, 399 - 160);
  EXPECT_DOUBLE_EQ(turned.end, 399 - 100);
  EXPECT_DOUBLE_EQ(turned.across_begin, 600);
  BeltReads reads;
  EXPECT_FALSE(reads.any_over({0, 1000, 0, 0}));
  reads.add(box);
  EXPECT_TRUE(reads.any_over({500, 620, 90, 170}));    // the code's downstream end, centre beyond
  EXPECT_TRUE(reads.any_over({500, 620, 0, 0}));       // lines not given: every line
  EXPECT_FALSE(reads.any_over({560, 700, 90, 170}));   // beyond it along the motion
  EXPECT_FALSE(reads.any_over({400, 500, 200, 260}));  // below it
}

TEST(SecondPassBudget, CreditFollowsTheFramePeriodTheWorkersAndTheFirstPass) {
  SecondPassBudget budget(-1, 2);  // auto
  budget.add_frame(0, 0, 20);      // no period yet: no credit
  EXPECT_EQ(budget.credit_ms(), 0);
  budget.add_frame(1, 16'666'667, 20);  // 60 fps, 2 workers: 33.3 x 0.85 - 20 = 8.3 ms
  EXPECT_NEAR(budget.credit_ms(), 2 * 16.666667 * SecondPassBudget::kShare - 20, 0.01);
  EXPECT_FALSE(budget.take(9));
  EXPECT_TRUE(budget.take(8));
  budget.settle(8, 10, 100'000);  // took 2 ms more than estimated: owed
  EXPECT_NEAR(budget.credit_ms(), 2 * 16.666667 * SecondPassBudget::kShare - 30, 0.01);
  for (int i = 2; i < 50; ++i) budget.add_frame(i, i * 16'666'667LL, 0);  // idle frames
  EXPECT_NEAR(budget.credit_ms(), 2 * 2 * 16.666667 * SecondPassBudget::kShare, 0.01);  // capped
  // The cost model follows what windows took: 10 ms for 0.1 Mpx -> 100 ms per Mpx, on the way.
  const double before = budget.estimate_ms(1'000'000);
  budget.settle(0, 10, 100'000);
  EXPECT_GT(budget.estimate_ms(1'000'000), before);

  SecondPassBudget fixed(5, 2);
  fixed.add_frame(0, 0, 1000);  // a fixed budget ignores the rate and the first pass
  EXPECT_EQ(fixed.credit_ms(), 5);
  SecondPassBudget none(0, 2);
  none.add_frame(0, 0, 0);
  EXPECT_FALSE(none.take(0.1));
}

TEST(SecondPassBudget, TheCamerasRateServesUntilTheTimestampsShowTheirOwn) {
  SecondPassBudget budget(-1, 2);
  EXPECT_EQ(budget.frame_share_ms(), 0);  // nothing known: the decode is not bounded
  budget.expect_period_ms(1000 / 60.0);   // the camera was set to 60 fps
  EXPECT_NEAR(budget.frame_share_ms(), 2 * 16.666667 * SecondPassBudget::kShare, 0.01);
  budget.add_frame(0, 0, 0);
  budget.add_frame(1, 33'333'333, 0);  // the timestamps show 30 fps: they replace it
  EXPECT_NEAR(budget.frame_share_ms(), 2 * 33.333333 * SecondPassBudget::kShare, 0.01);
  budget.expect_period_ms(10);  // and a rate set later does not override what they show
  EXPECT_NEAR(budget.frame_share_ms(), 2 * 33.333333 * SecondPassBudget::kShare, 0.01);
}

}  // namespace
}  // namespace flutterscan::session
