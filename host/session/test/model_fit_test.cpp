// The session's per-frame model choice and guards: a nominal grey frame keeps
// the simplest model with quiet guards; colour print switches to per-channel
// latents; a line without an encoder gets its blur from the frame; a wrong
// encoder reading is caught by the blur check; saturation is flagged.

#include <gtest/gtest.h>

#include <algorithm>

#include "imaging/frame_conversion.hpp"
#include "imaging/metrics.hpp"
#include "imaging/model_guards.hpp"
#include "imaging/test/label_capture.hpp"
#include "reader/barcode_reader.hpp"
#include "session/model_fit.hpp"
#include "sim/colour_scene.hpp"
#include "sim/forward_model.hpp"
#include "sim/scene.hpp"
#include "sim/timeline_forward.hpp"

namespace flutterscan::session {
namespace {

imaging::CaptureModel capture(double blur_px = 52, double electrons = 3000) {
  return test_fixtures::label_capture(
      {.blur_px = blur_px, .electrons = electrons, .black_level = 64});
}

sim::SceneSpec code128() {
  sim::SceneSpec spec;
  spec.kind = sim::SceneKind::kCode128;
  spec.content = "FIT-0042";
  return spec;
}

struct Frame {
  imaging::Image dn;
  imaging::MotionFrame electrons;  ///< as the session passes it: in the motion frame
};

Frame record(const imaging::Image& expected, const imaging::CaptureModel& m) {
  Frame f;
  f.dn = sim::record_frame(expected, m, 7);
  f.electrons = imaging::MotionFrame::make(imaging::dn_to_electrons(f.dn, m), m.direction).value();
  return f;
}

imaging::DeblurOptions tv() {
  imaging::DeblurOptions options;
  options.method = imaging::Method::kTotalVariation;
  return options;
}

bool has(const std::vector<std::string>& flags, const std::string& name) {
  return std::find(flags.begin(), flags.end(), name) != flags.end();
}

TEST(ModelFit, NominalGreyFrameKeepsTheSimplestModel) {
  const auto m = capture();
  const auto scene = sim::render_scene(code128()).value();
  const Frame f = record(sim::expected_electrons(scene, m), m);
  const auto fitted =
      deblur_fitting_model(imaging::saturated_share(f.dn, m), f.electrons, m, tv(), {}, 1);
  ASSERT_TRUE(fitted.ok()) << fitted.error();
  EXPECT_TRUE(fitted.value().flags.empty()) << fitted.value().log.dump();
  EXPECT_EQ(fitted.value().log["model"]["chosen"],
            "grey latent, global code phase, blur from the encoder");
  EXPECT_LT(fitted.value().log["guards"]["residual_ratio"].get<double>(), 1.5);
  EXPECT_EQ(reader::code_texts(reader::read_barcodes(fitted.value().latent)),
            std::vector<std::string>{"FIT-0042"});
}

TEST(ModelFit, ColourPrintGetsPerChannelLatents) {
  const auto m = capture();
  const auto bands = sim::render_colour_scene(code128(), sim::kRedInk).value();
  const Frame f = record(sim::expected_colour_electrons(bands, m).value(), m);
  const auto fitted =
      deblur_fitting_model(imaging::saturated_share(f.dn, m), f.electrons, m, tv(), {}, 1);
  ASSERT_TRUE(fitted.ok()) << fitted.error();
  EXPECT_EQ(fitted.value().log["model"]["chosen"],
            "per-channel latents, global code phase, blur from the encoder");
  EXPECT_EQ(reader::code_texts(reader::read_barcodes(fitted.value().latent)),
            std::vector<std::string>{"FIT-0042"});
}

TEST(ModelFit, WithoutAnEncoderTheBlurComesFromTheFrame) {
  const auto truth = capture(47.5);
  const auto scene = sim::render_scene(code128()).value();
  const Frame f = record(sim::expected_electrons(scene, truth), truth);
  ModelFitConfig config;
  config.encoder = false;
  // The nominal blur (from the configured belt speed) is 10% off.
  const auto fitted = deblur_fitting_model(imaging::saturated_share(f.dn, capture(52)), f.electrons,
                                           capture(52), tv(), config, 1);
  ASSERT_TRUE(fitted.ok()) << fitted.error();
  EXPECT_NEAR(fitted.value().log["model"]["blur_px"].get<double>(), 47.5, 0.3);
  EXPECT_EQ(fitted.value().log["model"]["chosen"],
            "grey latent, global code phase, blur estimated from the frame");
  EXPECT_EQ(reader::code_texts(reader::read_barcodes(fitted.value().latent)),
            std::vector<std::string>{"FIT-0042"});
}

TEST(ModelFit, TheBlurCheckCatchesAWrongEncoderReading) {
  const auto truth = capture(52);
  const auto scene = sim::render_scene(code128()).value();
  const Frame f = record(sim::expected_electrons(scene, truth), truth);
  ModelFitConfig config;
  config.blur_check_every = 1;
  config.blur_tolerance = 0;  // the encoder's blur used as it is
  const auto right = deblur_fitting_model(imaging::saturated_share(f.dn, capture(52)), f.electrons,
                                          capture(52), tv(), config, 1);
  ASSERT_TRUE(right.ok());
  EXPECT_FALSE(has(right.value().flags, "blur-disagrees")) << right.value().log.dump();
  const auto wrong = deblur_fitting_model(imaging::saturated_share(f.dn, capture(57)), f.electrons,
                                          capture(57), tv(), config, 1);
  ASSERT_TRUE(wrong.ok());
  EXPECT_TRUE(has(wrong.value().flags, "blur-disagrees")) << wrong.value().log.dump();
  // The deblurred frame's residual rises well above the right blur's (about 1). Under the
  // box-aperture pixel model a 10% error leaves 2.6 times the noise (the tap-grid model left
  // over 3, the misfit guard's level); the blur check is what catches it.
  EXPECT_GT(wrong.value().log["guards"]["residual_ratio"].get<double>(),
            2 * right.value().log["guards"]["residual_ratio"].get<double>())
      << wrong.value().log.dump();
}

TEST(ModelFit, RefinementCorrectsAWrongEncoderReading) {
  const auto truth = capture(52);
  const auto scene = sim::render_scene(code128()).value();
  const Frame f = record(sim::expected_electrons(scene, truth), truth);
  ModelFitConfig config;  // refinement on by default (10%)
  config.blur_check_every = 1;
  const auto wrong = deblur_fitting_model(imaging::saturated_share(f.dn, capture(57)), f.electrons,
                                          capture(57), tv(), config, 1);
  ASSERT_TRUE(wrong.ok());
  const auto& log = wrong.value().log;
  // The check still judges the encoder; the frame is deblurred with the refined blur.
  EXPECT_TRUE(has(wrong.value().flags, "blur-disagrees")) << log.dump();
  EXPECT_FALSE(has(wrong.value().flags, "misfit")) << log.dump();
  EXPECT_TRUE(log["motion"]["used"].get<bool>()) << log.dump();
  EXPECT_EQ(log["motion"]["encoder_blur_px"].get<double>(), 57.0);
  EXPECT_NEAR(log["motion"]["refined_blur_px"].get<double>(), 52.0, 0.05) << log.dump();
  EXPECT_NEAR(log["model"]["blur_px"].get<double>(), 52.0, 0.05) << log.dump();
  ASSERT_TRUE(wrong.value().refinement.has_value());
  EXPECT_TRUE(wrong.value().refinement_used);
  EXPECT_EQ(reader::code_texts(reader::read_barcodes(wrong.value().latent)),
            std::vector<std::string>{"FIT-0042"});

  // Told 30% wrong, the truth lies outside the tolerance: what the search finds either sits
  // on the tolerance's edge or leaves a residual far above the noise; flagged, not used.
  const auto far = deblur_fitting_model(imaging::saturated_share(f.dn, capture(68)), f.electrons,
                                        capture(68), tv(), config, 1);
  ASSERT_TRUE(far.ok());
  EXPECT_TRUE(has(far.value().flags, "blur-off-encoder") || has(far.value().flags, "motion-unfit"))
      << far.value().log.dump();
  EXPECT_FALSE(far.value().refinement_used);
  EXPECT_NEAR(far.value().log["model"]["blur_px"].get<double>(), 68.0, 1e-9);
}

// Behind (the session sets reuse_motion_ratio): no refinement; the encoder's
// blur scaled by the latest refined frame's ratio, flagged.
TEST(ModelFit, ABehindFrameTakesTheLatestRefinedRatioUnrefined) {
  const auto truth = capture(52);
  const auto scene = sim::render_scene(code128()).value();
  const Frame f = record(sim::expected_electrons(scene, truth), truth);
  ModelFitConfig config;  // refinement on by default (10%)
  config.reuse_motion_ratio = 52.0 / 57;
  const auto fit = deblur_fitting_model(imaging::saturated_share(f.dn, capture(57)), f.electrons,
                                        capture(57), tv(), config, 1);
  ASSERT_TRUE(fit.ok());
  const auto& log = fit.value().log;
  EXPECT_TRUE(has(fit.value().flags, "motion-reused")) << log.dump();
  EXPECT_FALSE(fit.value().refinement.has_value());
  EXPECT_FALSE(log["motion"]["used"].get<bool>()) << log.dump();
  EXPECT_FALSE(log["motion"].contains("refined_blur_px")) << log.dump();
  EXPECT_NEAR(log["model"]["blur_px"].get<double>(), 52.0, 1e-9) << log.dump();
  EXPECT_EQ(reader::code_texts(reader::read_barcodes(fit.value().latent)),
            std::vector<std::string>{"FIT-0042"});
}

TEST(ModelFit, SaturationIsFlagged) {
  const auto m = capture(52, 30000);
  const auto scene = sim::render_scene(code128()).value();
  const Frame f = record(sim::expected_electrons(scene, m), m);
  ModelFitConfig config;
  config.choose_latent = false;
  const auto fitted =
      deblur_fitting_model(imaging::saturated_share(f.dn, m), f.electrons, m, tv(), config, 1);
  ASSERT_TRUE(fitted.ok());
  EXPECT_TRUE(has(fitted.value().flags, "saturated")) << fitted.value().log.dump();
}

}  // namespace
}  // namespace flutterscan::session
