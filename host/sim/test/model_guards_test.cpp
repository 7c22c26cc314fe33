// Each guard fires on a simulated frame built to trip it and stays quiet on a
// nominal one.

#include <gtest/gtest.h>

#include "imaging/deblur.hpp"
#include "imaging/frame_conversion.hpp"
#include "imaging/model_guards.hpp"
#include "imaging/test/label_capture.hpp"
#include "sim/forward_model.hpp"
#include "sim/scene.hpp"

namespace flutterscan::sim {
namespace {

using imaging::CaptureModel;

CaptureModel label_capture(double electrons = 3000, double blur_px = 52) {
  return test_fixtures::label_capture(
      {.blur_px = blur_px, .electrons = electrons, .black_level = 64});
}

imaging::Plane code128() {
  SceneSpec spec;
  spec.kind = SceneKind::kCode128;
  spec.content = "GUARD-0042";
  return render_scene(spec).value();
}

/// Records `scene` under `truth`, deblurs it with `assumed` (tv), and runs the guards.
imaging::GuardReport guards(const imaging::Plane& scene, const CaptureModel& truth,
                            const CaptureModel& assumed) {
  const imaging::Image dn = record_frame(expected_electrons(scene, truth), truth, 9);
  const auto electrons =
      imaging::MotionFrame::make(imaging::dn_to_electrons(dn, assumed), assumed.direction);
  if (!electrons.ok()) {
    ADD_FAILURE() << electrons.error();
    return {};
  }
  imaging::DeblurOptions options;
  options.method = imaging::Method::kTotalVariation;
  const auto result = imaging::deblur(electrons.value(), assumed, options);
  EXPECT_TRUE(result.ok());
  imaging::GuardReport report;
  report.saturated_share = imaging::saturated_share(dn, assumed);
  report.residual_ratio =
      imaging::residual_ratio(electrons.value(), result.value().latent, assumed);
  return report;
}

TEST(ModelGuards, QuietOnANominalFrame) {
  const auto report = guards(code128(), label_capture(), label_capture());
  EXPECT_LT(report.saturated_share, imaging::kSaturationGuardShare);
  EXPECT_LT(report.residual_ratio, 1.5);
  EXPECT_TRUE(report.flags().empty());
}

TEST(ModelGuards, SaturationFires) {
  const auto report = guards(code128(), label_capture(30000), label_capture(30000));
  EXPECT_TRUE(report.saturated());
  EXPECT_EQ(report.flags().front(), "saturated");
}

TEST(ModelGuards, MisfitFiresOnAWrongBlurLength) {
  const auto report = guards(code128(), label_capture(3000, 52), label_capture(3000, 57));
  EXPECT_TRUE(report.misfit()) << report.residual_ratio;
  EXPECT_FALSE(report.saturated());
}

TEST(ModelGuards, BlurDisagreementFiresOutsideTheConfidence) {
  imaging::BlurEstimate estimate;
  estimate.blur_px = 52.1;
  estimate.standard_error_px = 0.05;
  EXPECT_FALSE(imaging::blur_disagrees(52.0, estimate));
  EXPECT_TRUE(imaging::blur_disagrees(55.0, estimate));
  estimate.standard_error_px = 2.0;  // a weak estimate allows more
  EXPECT_FALSE(imaging::blur_disagrees(55.0, estimate));
  estimate.standard_error_px = std::numeric_limits<double>::infinity();  // no estimate at all
  EXPECT_FALSE(imaging::blur_disagrees(80.0, estimate));
  // On a real frame: the estimate from the frame against a wrong encoder reading.
  const CaptureModel m = label_capture();
  const auto electrons = imaging::MotionFrame::make(
      imaging::dn_to_electrons(record_frame(expected_electrons(code128(), m), m, 4), m),
      m.direction);
  ASSERT_TRUE(electrons.ok()) << electrons.error();
  const auto measured = imaging::estimate_blur(electrons.value(), m, 30, 80);
  ASSERT_TRUE(measured.ok()) << measured.error();
  EXPECT_FALSE(imaging::blur_disagrees(52.0, measured.value()));
  EXPECT_TRUE(imaging::blur_disagrees(57.2, measured.value()));
}

}  // namespace
}  // namespace flutterscan::sim
