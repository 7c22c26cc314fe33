// The edge-preserving joint method ("tv") on simulated label frames: it must
// beat joint Wiener clearly, stay a reflectance, work for every motion
// direction and not drift away when given more iterations.

#include <gtest/gtest.h>

#include <algorithm>

#include "imaging/capture_descriptor.hpp"
#include "imaging/deblur.hpp"
#include "imaging/frame_conversion.hpp"
#include "imaging/metrics.hpp"
#include "imaging/motion_frame.hpp"
#include "imaging/test/label_capture.hpp"
#include "sim/forward_model.hpp"
#include "sim/scene.hpp"

namespace flutterscan::sim {
namespace {

using imaging::CaptureModel;
using imaging::DeblurOptions;
using imaging::Direction;
using imaging::Method;
using imaging::Plane;

/// The seed's max-min triplet.
constexpr const char* kSeedMaxMin = "2212441414112412441224111241244244242212442211444144";

/// The imaging issue's capture: `code` (default the seed max-min triplet), `electrons`
/// per channel, cap 3, 52 px blur, crosstalk, 4 e- read noise, 12 bits over a 12000 e- well.
CaptureModel label_capture(Direction direction = Direction::kPlusX, const char* code = kSeedMaxMin,
                           double electrons = 3000) {
  return test_fixtures::label_capture(
      {.code = code, .electrons = electrons, .direction = direction});
}

/// A Code 128 label, rows along +x.
Plane code128_label() {
  SceneSpec spec;
  spec.kind = SceneKind::kCode128;
  spec.content = "FLUTTER-0042";
  const auto scene = render_scene(spec);
  EXPECT_TRUE(scene.ok()) << (scene.ok() ? "" : scene.error());
  return scene.ok() ? scene.value() : Plane(spec.width, spec.height, 0.5f);
}

/// A Data Matrix label: edges across the rows as well as along them (tv converges last here).
Plane data_matrix_label() {
  SceneSpec spec;
  spec.kind = SceneKind::kDataMatrix;
  spec.content = "LOT-2611";
  const auto scene = render_scene(spec);
  EXPECT_TRUE(scene.ok()) << (scene.ok() ? "" : scene.error());
  return scene.ok() ? scene.value() : Plane(spec.width, spec.height, 0.5f);
}

Plane deblurred(const Plane& scene, const CaptureModel& m, const DeblurOptions& options) {
  const auto frame = imaging::dn_to_electrons(record_frame(expected_electrons(scene, m), m, 1), m);
  const auto result = imaging::deblur(frame, m, options);
  EXPECT_TRUE(result.ok()) << (result.ok() ? "" : result.error());
  return result.ok() ? result.value().latent : Plane(scene.width, scene.height);
}

double score(const Plane& scene, const Plane& estimate, const CaptureModel& m) {
  return imaging::psnr(scene, estimate,
                       imaging::scored_region(scene.width, scene.height, m.blur_px, m.direction));
}

DeblurOptions tv_options(int iterations = 0) {
  DeblurOptions options;
  options.method = Method::kTotalVariation;
  if (iterations > 0) options.iterations = iterations;
  return options;
}

TEST(TotalVariation, NamedTv) {
  EXPECT_EQ(imaging::method_name(Method::kTotalVariation), "tv");
  EXPECT_EQ(imaging::method_from_name("tv"), Method::kTotalVariation);
}

TEST(TotalVariation, BeatsJointWienerOnACode128Label) {
  const Plane scene = code128_label();
  const CaptureModel m = label_capture();
  const double wiener = score(scene, deblurred(scene, m, {}), m);
  const double tv = score(scene, deblurred(scene, m, tv_options()), m);
  EXPECT_GT(wiener, 20.0);
  EXPECT_GT(tv, wiener + 5.0) << "joint Wiener " << wiener << " dB";
}

TEST(TotalVariation, TheL0PriorAlsoBeatsJointWiener) {
  const Plane scene = code128_label();
  const CaptureModel m = label_capture();
  DeblurOptions l0 = tv_options();
  l0.edge_prior = imaging::EdgePrior::kL0Gradient;
  EXPECT_GT(score(scene, deblurred(scene, m, l0), m),
            score(scene, deblurred(scene, m, {}), m) + 5.0);
}

TEST(TotalVariation, ResultIsAReflectance) {
  const Plane scene = code128_label();
  const Plane latent = deblurred(scene, label_capture(), tv_options());
  ASSERT_EQ(latent.width, scene.width);
  ASSERT_EQ(latent.height, scene.height);
  const auto [lowest, highest] = std::minmax_element(latent.pixels.begin(), latent.pixels.end());
  EXPECT_GE(*lowest, 0.0f);
  EXPECT_LE(*highest, 1.0f);
  EXPECT_LT(*lowest, 0.2f);   // ink is recovered ...
  EXPECT_GT(*highest, 0.7f);  // ... and so is paper
}

TEST(TotalVariation, EveryDirectionGivesTheSameQuality) {
  const Plane along_x = code128_label();
  const CaptureModel plus_x = label_capture();
  const double reference = score(along_x, deblurred(along_x, plus_x, tv_options()), plus_x);
  for (Direction d : {Direction::kMinusX, Direction::kPlusY, Direction::kMinusY}) {
    const CaptureModel m = label_capture(d);
    const Plane scene = imaging::from_motion_frame(along_x, d);
    const double tv = score(scene, deblurred(scene, m, tv_options()), m);
    EXPECT_NEAR(tv, reference, 0.5) << imaging::direction_name(d);
    EXPECT_GT(tv, score(scene, deblurred(scene, m, {}), m) + 5.0) << imaging::direction_name(d);
  }
}

// The prior's weight follows the noise: with a fixed weight the MAP estimate
// stopped improving above about 1000 e- and scored 1.5 dB lower at 10000 e- than
// at 3000 e-.
TEST(TotalVariation, MoreLightGivesABetterEstimate) {
  const Plane scene = code128_label();
  double previous = 0;
  for (double electrons : {300.0, 1000.0, 3000.0, 10000.0}) {
    const CaptureModel m = label_capture(Direction::kPlusX, kSeedMaxMin, electrons);
    const double tv = score(scene, deblurred(scene, m, tv_options()), m);
    EXPECT_GT(tv, previous + 2.0) << electrons << " e-";
    previous = tv;
  }
}

// The imaging issue's target on one label: the best triplet (found-mse) beats
// all LEDs fluttering together by Raskar's code, both with tv, at 3000 e-, c = 3
// (docs/benchmarks.md has the full sweep). With the tap-grid pixel model the margin
// was 3.7 dB and this asserted 2 dB; through the box aperture (every PSF smoothed by
// the pixel, which narrows the coded spectra's advantage at high frequencies) it is
// 1.77 dB: asserted at 1.5, the figure written in the note.
TEST(TotalVariation, BestTripletBeatsRaskarWhite) {
  const Plane scene = code128_label();
  const CaptureModel triplet =
      label_capture(Direction::kPlusX, "4242221144411121214241142422112112214412414144224412");
  const CaptureModel raskar =
      label_capture(Direction::kPlusX, "7070000777000007070000770077770777070777007007700777");
  const double triplet_db = score(scene, deblurred(scene, triplet, tv_options()), triplet);
  const double raskar_db = score(scene, deblurred(scene, raskar, tv_options()), raskar);
  EXPECT_GT(triplet_db, raskar_db + 1.5) << "Raskar-white " << raskar_db << " dB";
}

TEST(TotalVariation, MoreIterationsDoNotDiverge) {
  const Plane scene = code128_label();
  const CaptureModel m = label_capture();
  const int iterations = imaging::kTotalVariationIterations;
  const double once = score(scene, deblurred(scene, m, tv_options(iterations)), m);
  const double twice = score(scene, deblurred(scene, m, tv_options(2 * iterations)), m);
  const double four_times = score(scene, deblurred(scene, m, tv_options(4 * iterations)), m);
  EXPECT_GT(twice, once - 0.3);
  EXPECT_GT(four_times, twice - 0.3);
}

// The default iterations stop close to the minimum even on the label that converges
// last: here 15 iterations were 0.59 dB below 160 (on tv_iterations' scenes 0.6 dB
// on the Data Matrix, 0.0-0.1 dB on the barcodes, as 40 of the earlier solver were).
TEST(TotalVariation, DefaultIterationsLandNearTheMinimumOnADataMatrix) {
  const Plane scene = data_matrix_label();
  const CaptureModel m = label_capture();
  const double standard = score(scene, deblurred(scene, m, tv_options()), m);
  const double converged = score(scene, deblurred(scene, m, tv_options(160)), m);
  EXPECT_GT(standard, converged - 0.8) << "160 iterations: " << converged << " dB";
}

// Rows are split between the threads, and so are the frequency bins of the solve
// across the rows: every row and every bin is computed the same way on any thread.
TEST(TotalVariation, ThreadCountDoesNotChangeTheResult) {
  const Plane scene = data_matrix_label();
  const CaptureModel m = label_capture();
  DeblurOptions one = tv_options(), three = tv_options();
  one.threads = 1;
  three.threads = 3;
  EXPECT_EQ(deblurred(scene, m, one).pixels, deblurred(scene, m, three).pixels);
}

}  // namespace
}  // namespace flutterscan::sim
