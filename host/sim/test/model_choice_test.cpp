// The pipeline's model choice: a grey label keeps the grey model, a label in
// red or blue print is recognised as colour; rolling shutter and the encoder
// are taken from the configuration.

#include <gtest/gtest.h>

#include "imaging/frame_conversion.hpp"
#include "imaging/model_choice.hpp"
#include "imaging/motion_frame.hpp"
#include "imaging/test/label_capture.hpp"
#include "sim/colour_scene.hpp"
#include "sim/forward_model.hpp"
#include "sim/timeline_forward.hpp"

namespace flutterscan::sim {
namespace {

imaging::CaptureModel label_capture() {
  return test_fixtures::label_capture({.black_level = 64});
}

SceneSpec code128() {
  SceneSpec spec;
  spec.kind = SceneKind::kCode128;
  spec.content = "COLOUR-42";
  return spec;
}

/// The recorded frame in electrons, in the motion frame.
imaging::MotionFrame electrons_of(const imaging::Image& expected, const imaging::CaptureModel& m) {
  return imaging::MotionFrame::make(imaging::dn_to_electrons(record_frame(expected, m, 3), m),
                                    m.direction)
      .value();
}

TEST(ModelChoice, GreyLabelKeepsTheGreyModel) {
  const auto m = label_capture();
  const auto scene = render_scene(code128()).value();
  const auto choice =
      imaging::choose_frame_model(electrons_of(expected_electrons(scene, m), m), m, false, true);
  EXPECT_EQ(choice.latent, imaging::LatentModel::kGrey) << choice.grey_residual;
  EXPECT_LT(choice.grey_residual, 1.5);
  EXPECT_EQ(choice.describe(), "grey latent, global code phase, blur from the encoder");
}

TEST(ModelChoice, ColourPrintNeedsPerChannelLatents) {
  const auto m = label_capture();
  for (const auto& ink : {kRedInk, kBlueInk}) {
    const auto bands = render_colour_scene(code128(), ink);
    ASSERT_TRUE(bands.ok()) << bands.error();
    const auto expected = expected_colour_electrons(bands.value(), m);
    ASSERT_TRUE(expected.ok()) << expected.error();
    const auto choice =
        imaging::choose_frame_model(electrons_of(expected.value(), m), m, true, false);
    EXPECT_EQ(choice.latent, imaging::LatentModel::kPerChannel) << choice.grey_residual;
    EXPECT_EQ(choice.describe(),
              "per-channel latents, per-row code phase, blur estimated from the frame");
  }
}

}  // namespace
}  // namespace flutterscan::sim
