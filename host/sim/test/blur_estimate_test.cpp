// The blur estimator on simulated coded frames: it finds the true blur (also
// fractional, in every direction) within its stated confidence, and refuses
// frames that carry no blur information.

#include <gtest/gtest.h>

#include <cmath>

#include "imaging/blur_estimate.hpp"
#include "imaging/capture_descriptor.hpp"
#include "imaging/frame_conversion.hpp"
#include "imaging/motion_frame.hpp"
#include "imaging/test/label_capture.hpp"
#include "sim/forward_model.hpp"
#include "sim/scene.hpp"

namespace flutterscan::sim {
namespace {

using imaging::CaptureModel;
using imaging::Direction;

CaptureModel triplet_capture(double blur_px, const char* code = test_fixtures::kFoundMse) {
  return test_fixtures::label_capture({.code = code, .blur_px = blur_px});
}

imaging::Plane label(SceneKind kind, const char* content) {
  SceneSpec spec;
  spec.kind = kind;
  spec.content = content;
  const auto scene = render_scene(spec);
  EXPECT_TRUE(scene.ok());
  return scene.value();
}

/// The recorded frame in electrons, turned into the motion frame as the session does.
imaging::MotionFrame recorded(const imaging::Plane& scene, const CaptureModel& m,
                              std::uint64_t seed) {
  return imaging::MotionFrame::make(
             imaging::dn_to_electrons(record_frame(expected_electrons(scene, m), m, seed), m),
             m.direction)
      .value();
}

TEST(BlurEstimate, FindsTheTrueBlurWithinItsConfidence) {
  const auto scene = label(SceneKind::kCode128, "FLUTTER-0042");
  for (double truth : {37.3, 52.0, 71.6}) {
    const CaptureModel m = triplet_capture(truth);
    const auto estimate = imaging::estimate_blur(recorded(scene, m, 7), m, 20, 100);
    ASSERT_TRUE(estimate.ok()) << estimate.error();
    EXPECT_NEAR(estimate.value().blur_px, truth, 0.25) << truth;
    EXPECT_LT(estimate.value().standard_error_px, 0.2)
        << truth << " contrast " << estimate.value().contrast;
    EXPECT_GT(estimate.value().contrast, 1.0) << truth;
    EXPECT_NEAR(estimate.value().residual_per_sample, 1.0, 0.3) << truth;
    // Honest confidence: the error is within a few standard errors (or 0.05 px).
    EXPECT_LT(std::abs(estimate.value().blur_px - truth),
              std::max(0.05, 4 * estimate.value().standard_error_px))
        << truth;
  }
}

TEST(BlurEstimate, WorksAlongEveryDirection) {
  const auto along_x = label(SceneKind::kEan13, "4006381333931");
  for (Direction d : {Direction::kMinusX, Direction::kPlusY, Direction::kMinusY}) {
    CaptureModel m = triplet_capture(48.5);
    m.direction = d;
    const auto scene = imaging::from_motion_frame(along_x, d);
    const auto estimate = imaging::estimate_blur(recorded(scene, m, 3), m, 20, 100);
    ASSERT_TRUE(estimate.ok()) << estimate.error();
    EXPECT_NEAR(estimate.value().blur_px, 48.5, 0.3) << imaging::direction_name(d);
  }
}

TEST(BlurEstimate, AFlatSceneGivesNoConfidentAnswer) {
  const imaging::Plane flat(640, 360, 0.8f);
  const CaptureModel m = triplet_capture(52);
  const auto estimate = imaging::estimate_blur(recorded(flat, m, 5), m, 20, 100);
  ASSERT_TRUE(estimate.ok()) << estimate.error();
  EXPECT_TRUE(std::isinf(estimate.value().standard_error_px))
      << estimate.value().blur_px << " px, contrast " << estimate.value().contrast;
}

TEST(BlurEstimate, RefusesFramesWithoutBlurInformation) {
  const auto scene = label(SceneKind::kCode128, "FLUTTER-0042");
  const CaptureModel white =
      triplet_capture(52, "7070000777000007070000770077770777070777007007700777");
  const auto shared = imaging::estimate_blur(recorded(scene, white, 1), white, 20, 100);
  ASSERT_FALSE(shared.ok());
  EXPECT_NE(shared.error().find("same code"), std::string::npos) << shared.error();
  const CaptureModel m = triplet_capture(52);
  EXPECT_FALSE(imaging::estimate_blur(recorded(scene, m, 1), m, 60, 40).ok());
  EXPECT_FALSE(imaging::estimate_blur(recorded(scene, m, 1), m, 20, 900).ok());
}

}  // namespace
}  // namespace flutterscan::sim
