// Per-frame motion refinement (imaging/motion_refinement.hpp) on frames of a
// scene that moves continuously within each pixel (rendered finer than the
// pixels): the blur told wrong by up to the tolerance is refined to the true
// one, a speed change within the exposure is found, and frames without edges
// along the motion keep the motion they were given.

#include "imaging/motion_refinement.hpp"

#include <gtest/gtest.h>

#include <random>

#include <cmath>

#include "imaging/capture_descriptor.hpp"
#include "imaging/deblur.hpp"
#include "imaging/exposure_timeline.hpp"
#include "imaging/frame_conversion.hpp"
#include "imaging/metrics.hpp"
#include "imaging/motion_frame.hpp"
#include "imaging/test/label_capture.hpp"
#include "sim/forward_model.hpp"
#include "sim/pixel_integration.hpp"
#include "sim/scene.hpp"
#include "sim/speed_profile.hpp"
#include "sim/timeline_forward.hpp"

namespace flutterscan::sim {
namespace {

using imaging::CaptureModel;
using imaging::Direction;

CaptureModel triplet_capture(double blur_px, double electrons) {
  return test_fixtures::label_capture({.blur_px = blur_px, .electrons = electrons});
}

imaging::Plane fine_label(SceneKind kind, const char* content, double module_px = 3) {
  SceneSpec spec;
  spec.kind = kind;
  spec.content = content;
  spec.module_px = module_px;
  const auto scene = render_scene(spec, kSimSupersample);
  EXPECT_TRUE(scene.ok());
  return scene.value();
}

/// The recorded frame in electrons, turned into the motion frame as the session does.
imaging::MotionFrame recorded(const imaging::Plane& fine, const CaptureModel& m,
                              std::uint64_t seed) {
  return imaging::MotionFrame::make(
             imaging::dn_to_electrons(
                 record_frame(expected_electrons(fine, m, kSimSupersample), m, seed), m),
             m.direction)
      .value();
}

TEST(MotionRefinement, FindsTheTrueBlurFromOneTenPercentOff) {
  const auto scene = fine_label(SceneKind::kCode128, "FLUTTER-0042");
  for (double electrons : {300.0, 1000.0, 3000.0, 10000.0}) {
    double squared = 0;
    int count = 0;
    for (double told : {48.0, 49.5, 54.0, 56.5}) {  // 52 within +-10% of each
      const CaptureModel truth = triplet_capture(52.0, electrons);
      CaptureModel assumed = truth;
      assumed.blur_px = told;
      const auto r = imaging::refine_motion(recorded(scene, truth, count + 11), assumed, {});
      ASSERT_TRUE(r.ok()) << r.error();
      EXPECT_TRUE(r.value().edges) << electrons << " " << told;
      EXPECT_FALSE(r.value().accelerating) << electrons << " " << told;
      squared += std::pow(r.value().blur_px - 52.0, 2);
      std::printf("%g e- told %g: %.3f +- %.3f px contrast %.2f residual %.3f\n", electrons, told,
                  r.value().blur_px, r.value().standard_error_px, r.value().contrast,
                  r.value().residual_per_sample);
      ++count;
      // An honest confidence: within 4 standard errors (or 0.05 px).
      EXPECT_LT(std::abs(r.value().blur_px - 52.0), std::max(0.05, 4 * r.value().standard_error_px))
          << electrons << " " << told;
    }
    EXPECT_LT(std::sqrt(squared / count), 0.05) << electrons << " e-";
  }
}

TEST(MotionRefinement, TheToleranceHoldsEitherWayAndFlagsAnEncoderBeyondIt) {
  // An encoder 10% low of the truth (46.8 for 52) is within a 10% tolerance read
  // of the truth; 20% low is not, and says so rather than settling on the range's edge.
  const auto scene = fine_label(SceneKind::kCode128, "FLUTTER-0042");
  const CaptureModel truth = triplet_capture(52.0, 3000);
  const auto frame = recorded(scene, truth, 21);
  for (double told : {46.8, 57.2, 41.6}) {
    CaptureModel assumed = truth;
    assumed.blur_px = told;
    const auto r = imaging::refine_motion(frame, assumed, {});
    ASSERT_TRUE(r.ok()) << r.error();
    ASSERT_TRUE(r.value().edges) << told;
    const bool within = told > 45;
    // Beyond the tolerance: on the search's edge, or a motion that does not fit.
    EXPECT_EQ(r.value().outside_tolerance ||
                  r.value().residual_per_sample > imaging::kUnfitMotionResidual,
              !within)
        << told << ": " << r.value().blur_px << " residual " << r.value().residual_per_sample;
    EXPECT_EQ(imaging::refinement_usable(r.value()), within) << told;
    if (within) {
      EXPECT_NEAR(r.value().blur_px, 52.0, 0.05) << told;
    }
  }
}

TEST(MotionRefinement, WorksAlongEveryDirection) {
  const auto along_x = fine_label(SceneKind::kEan13, "4006381333931");
  for (Direction d : {Direction::kMinusX, Direction::kPlusY, Direction::kMinusY}) {
    CaptureModel m = triplet_capture(48.5, 3000);
    m.direction = d;
    const auto scene = imaging::from_motion_frame(along_x, d);
    CaptureModel assumed = m;
    assumed.blur_px = 51;
    const auto r = imaging::refine_motion(recorded(scene, m, 3), assumed, {});
    ASSERT_TRUE(r.ok()) << r.error();
    EXPECT_NEAR(r.value().blur_px, 48.5, 0.1) << imaging::direction_name(d);
  }
}

TEST(MotionRefinement, FramesWithoutEdgesKeepTheirMotion) {
  const imaging::Plane flat(640 * kSimSupersample, 360 * kSimSupersample, 0.8f);
  CaptureModel m = triplet_capture(52, 3000);
  CaptureModel assumed = m;
  assumed.blur_px = 50;
  const auto r = imaging::refine_motion(recorded(flat, m, 5), assumed, {});
  ASSERT_TRUE(r.ok()) << r.error();
  EXPECT_FALSE(r.value().edges);
  EXPECT_FALSE(r.value().accelerating);
  EXPECT_EQ(r.value().blur_px, 50);
  EXPECT_TRUE(std::isinf(r.value().standard_error_px));
}

// Faint print on a few rows at 300 e-: the edgiest rows come first, the rows
// after them are belt and only dilute what the first showed, so the search
// stops once a batch lowered the significance instead of reading every row.

constexpr float kFaintContrast =
    0.28f;  // 300 e-: significance above 10 on the bars' rows, below 20 with the belt's
TEST(MotionRefinement, AFrameWhoseRowsAddedLowerTheSignificanceStopsReading) {
  // Bars 2-8 px wide (fine pixels x kSimSupersample) of +-kFaintContrast on 40 rows of a mid-grey
  // belt.
  imaging::Plane faint(640 * kSimSupersample, 360 * kSimSupersample, 0.5f);
  std::mt19937 random(3);
  std::vector<float> bars(static_cast<std::size_t>(faint.width));
  for (std::size_t x = 0; x < bars.size();) {
    const std::size_t run = (2 + random() % 7) * kSimSupersample;
    const float v = random() % 2 ? 0.5f + kFaintContrast : 0.5f - kFaintContrast;
    for (std::size_t i = 0; i < run && x < bars.size(); ++i, ++x) bars[x] = v;
  }
  for (int y = 100 * kSimSupersample; y < 140 * kSimSupersample; ++y)
    for (int x = 0; x < faint.width; ++x) faint.at(x, y) = bars[static_cast<std::size_t>(x)];
  const CaptureModel m = triplet_capture(52, 300);
  const auto r = imaging::refine_motion(recorded(faint, m, 9), m, {});
  ASSERT_TRUE(r.ok()) << r.error();
  EXPECT_FALSE(r.value().edges);
  EXPECT_EQ(r.value().blur_px, 52);
  EXPECT_LT(r.value().rows_used, imaging::MotionRefinementOptions{}.rows);
}

TEST(MotionRefinement, FindsASpeedChangeOnlyWhenThereIsOne) {
  const auto scene = fine_label(SceneKind::kCode128, "FLUTTER-0042");
  for (double ratio : {1.5, 0.7}) {
    CaptureModel truth = triplet_capture(52, 3000);
    truth.speed_ratio = ratio;
    CaptureModel assumed = truth;
    assumed.speed_ratio = 1;
    assumed.blur_px = 50;
    const auto r = imaging::refine_motion(recorded(scene, truth, 9), assumed, {});
    ASSERT_TRUE(r.ok()) << r.error();
    EXPECT_TRUE(r.value().accelerating) << ratio;
    EXPECT_NEAR(r.value().speed_ratio, ratio, 0.1 * ratio) << ratio;
    EXPECT_NEAR(r.value().blur_px, 52, 0.5) << ratio;
    EXPECT_LT(r.value().residual_per_sample, r.value().constant_speed_residual) << ratio;
  }
  const CaptureModel steady = triplet_capture(52, 3000);
  const auto r = imaging::refine_motion(recorded(scene, steady, 9), steady, {});
  ASSERT_TRUE(r.ok()) << r.error();
  EXPECT_FALSE(r.value().accelerating);
  EXPECT_EQ(r.value().speed_ratio, 1);
}

/// Root mean square distance of `edges` from `truth` (slot edges, px).
double edge_error(const std::vector<double>& edges, const std::vector<double>& truth) {
  double sum = 0;
  for (std::size_t t = 0; t < truth.size(); ++t) sum += std::pow(edges[t] - truth[t], 2);
  return std::sqrt(sum / static_cast<double>(truth.size()));
}

TEST(MotionRefinement, FollowsABeltThatJittersWithinTheExposure) {
  // Belt jitter of 0.2 rms per slot (speed), the total travel as the encoder says: a random walk
  // of about 0.7 px rms around the constant-speed edges, which no one- or two-parameter motion
  // follows. The wandering motion (block offsets) brings the edges closer and the deblur with it.
  const auto scene = fine_label(SceneKind::kCode128, "FLUTTER-0042");
  int wandering = 0;
  double before_sum = 0, after_sum = 0, psnr_before = 0, psnr_after = 0;
  const imaging::Region scored = imaging::scored_region(
      scene.width / kSimSupersample, scene.height / kSimSupersample, 52, Direction::kPlusX);
  const imaging::Plane truth_grey = bin_pixels(scene, kSimSupersample);
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    const CaptureModel m = triplet_capture(52, 3000);
    const auto edges = jittered_slot_boundaries(m.code.length(), 52, 0.2, seed * 3 + 1);
    const auto frame =
        imaging::MotionFrame::make(
            imaging::dn_to_electrons(
                record_frame(expected_electrons_timeline(
                                 scene, m, imaging::segments_from_boundaries(m.code, edges),
                                 kSimSupersample),
                             m, seed),
                m),
            m.direction)
            .value();
    const auto r = imaging::refine_motion(frame, m, {});
    ASSERT_TRUE(r.ok()) << r.error();
    ASSERT_TRUE(r.value().edges) << seed;
    wandering += r.value().wandering;
    const auto refined = imaging::with_refined_motion(m, r.value());
    const double before = edge_error(imaging::slot_edges(m), edges);
    const double after = edge_error(imaging::slot_edges(refined), edges);
    before_sum += before;
    after_sum += after;
    imaging::DeblurOptions options;
    options.method = imaging::Method::kJointWiener;
    const double p0 =
        imaging::psnr(truth_grey, imaging::deblur(frame, m, options).value().latent, scored);
    const double p1 =
        imaging::psnr(truth_grey, imaging::deblur(frame, refined, options).value().latent, scored);
    psnr_before += p0;
    psnr_after += p1;
    std::printf(
        "seed %d: edges %.3f -> %.3f px rms, residual %.2f -> %.2f, joint Wiener %.1f -> "
        "%.1f dB, wandering %d\n",
        static_cast<int>(seed), before, after, r.value().constant_speed_residual,
        r.value().residual_per_sample, p0, p1, r.value().wandering);
  }
  EXPECT_GE(wandering, 3);
  EXPECT_LT(after_sum, 0.6 * before_sum);
  EXPECT_GT(psnr_after, psnr_before + 4 * 1.0);  // over four frames: > 1 dB each on average
}

TEST(MotionRefinement, GivenOffsetsThatGoBackwardsAtAShorterBlurAreSkippedThere) {
  // Every other slot nearly still at 52 px (offsets valid there): at the shorter blurs the
  // search tries, those slots would run backwards; such motions are not candidates.
  const auto scene = fine_label(SceneKind::kCode128, "FLUTTER-0042");
  CaptureModel m = triplet_capture(52, 3000);
  for (int t = 1; t < m.code.length(); ++t) m.block_offsets_px.push_back(t % 2 ? -0.97 : 0.0);
  ASSERT_EQ(imaging::capture_model_problem(m), "");
  const auto frame = recorded(scene, m, 4);
  const auto r = imaging::refine_motion(frame, m, {});
  ASSERT_TRUE(r.ok()) << r.error();
  EXPECT_TRUE(r.value().edges);
  EXPECT_NEAR(r.value().blur_px, 52, 0.5);
}

TEST(MotionRefinement, RefusesWhatItCannotDo) {
  const auto scene = fine_label(SceneKind::kCode128, "FLUTTER-0042");
  const CaptureModel m = triplet_capture(52, 3000);
  const auto frame = recorded(scene, m, 1);
  for (double bad : {-0.1, 1.0, 1.5, double{NAN}, double{INFINITY}}) {
    imaging::MotionRefinementOptions options;
    options.tolerance = bad;
    const auto r = imaging::refine_motion(frame, m, options);
    ASSERT_FALSE(r.ok()) << bad;
    EXPECT_NE(r.error().find("tolerance"), std::string::npos) << r.error();
  }
  CaptureModel white = m;
  white.code = LedCode::parse(std::string(52, '7'), 3).value();
  EXPECT_FALSE(imaging::refine_motion(frame, white, {}).ok());
  CaptureModel huge = m;
  huge.blur_px = 600;
  const auto r = imaging::refine_motion(frame, huge, {});
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().find("does not fit"), std::string::npos) << r.error();
}

}  // namespace
}  // namespace flutterscan::sim
