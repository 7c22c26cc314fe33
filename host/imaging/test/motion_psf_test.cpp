// The pixel model (motion_psf.hpp): a slot's light laid onto the pixels
// through a box aperture, checked against its definition by numerical
// integration, and the motion of a constant acceleration.

#include "imaging/motion_psf.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numeric>
#include <random>

#include "imaging/capture_model.hpp"

namespace flutterscan::imaging {
namespace {

double sum(const std::vector<double>& v) {
  return std::accumulate(v.begin(), v.end(), 0.0);
}

TEST(MotionPsf, OnePixelPerSlotGivesHalfTapsAtTheEnds) {
  // One LED on in all four slots, one pixel of motion per slot: each slot is
  // [0.5, 0.5] over its two pixels, so the PSF is [0.5, 1, 1, 1, 0.5].
  CaptureModel m;
  m.code = LedCode::parse("1111", 1).value();
  m.channels = 1;
  m.leds = 1;
  m.crosstalk = {1};
  m.led_electrons = {1};
  m.ambient_electrons = {0};
  m.blur_px = 4;
  const auto taps = channel_psf(m, 0);
  const std::vector<double> expected = {0.5, 1, 1, 1, 0.5};
  ASSERT_EQ(taps.size(), expected.size());
  for (std::size_t j = 0; j < taps.size(); ++j) EXPECT_NEAR(taps[j], expected[j], 1e-12) << j;

  m.pixel_model = PixelModel::kTapGrid;  // the older model: one whole tap per slot
  const auto grid = channel_psf(m, 0);
  ASSERT_EQ(grid.size(), 4u);
  for (double t : grid) EXPECT_NEAR(t, 1.0, 1e-12);
}

TEST(MotionPsf, AStillSceneIsTheIdentityOrALinearInterpolation) {
  std::vector<double> taps(pixel_model_taps(0, PixelModel::kBoxAperture), 0.0);
  deposit_slot(taps, 0, 0, 2.0, PixelModel::kBoxAperture);
  EXPECT_NEAR(taps[0], 2.0, 1e-12);
  EXPECT_NEAR(taps[1], 0.0, 1e-12);
  std::vector<double> shifted(pixel_model_taps(3.25, PixelModel::kBoxAperture), 0.0);
  deposit_slot(shifted, 3.25, 0, 1.0, PixelModel::kBoxAperture);
  EXPECT_NEAR(shifted[3], 0.75, 1e-12);
  EXPECT_NEAR(shifted[4], 0.25, 1e-12);
}

TEST(MotionPsf, EachTapIsTheMeanOfTheTriangleOverTheSlot) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> start(0, 20), width(0.01, 6);
  for (int trial = 0; trial < 50; ++trial) {
    const double a = start(rng), w = width(rng);
    std::vector<double> taps(pixel_model_taps(a + w, PixelModel::kBoxAperture), 0.0);
    deposit_slot(taps, a, w, 1.0, PixelModel::kBoxAperture);
    EXPECT_NEAR(sum(taps), 1.0, 1e-12);  // light is conserved
    for (std::size_t j = 0; j < taps.size(); ++j) {
      constexpr int kSteps = 20000;  // midpoint rule
      double integral = 0;
      for (int s = 0; s < kSteps; ++s) {
        const double d = a + w * (s + 0.5) / kSteps;
        integral += std::max(0.0, 1 - std::abs(static_cast<double>(j) - d));
      }
      EXPECT_NEAR(taps[j], integral / kSteps, 1e-6) << a << " " << w << " tap " << j;
    }
  }
}

TEST(MotionPsf, AcceleratingEdgesTravelTheBlurWithTheSpeedRatio) {
  for (double ratio : {0.5, 1.0, 1.5, 2.0}) {
    const auto edges = accelerating_slot_edges(52, 52, ratio);
    ASSERT_EQ(edges.size(), 53u);
    EXPECT_NEAR(edges.front(), 0, 1e-12);
    EXPECT_NEAR(edges.back(), 52, 1e-9);
    // Slot widths are the speed at the slot's middle: last / first -> ratio.
    const double first = edges[1] - edges[0], last = edges[52] - edges[51];
    const double expected = (1 + (ratio - 1) * 51.5 / 52) / (1 + (ratio - 1) * 0.5 / 52);
    EXPECT_NEAR(last / first, expected, 1e-9) << ratio;
    for (std::size_t t = 1; t < edges.size(); ++t) EXPECT_GT(edges[t], edges[t - 1]);
  }
}

TEST(MotionPsf, ChannelPsfKeepsTheWhiteLevelWhateverTheMotion) {
  CaptureModel m;
  m.code = LedCode::parse("4242221144411121214241142422112112214412414144224412", 3).value();
  m.led_electrons = budgeted_led_electrons(m.code, 3000, 3);
  m.ambient_electrons = {40, 0, 10};
  for (double blur : {0.0, 13.3, 52.0, 77.7})
    for (double ratio : {1.0, 1.5, 0.7})
      for (PixelModel pixel :
           {PixelModel::kBoxAperture, PixelModel::kBandLimited, PixelModel::kTapGrid}) {
        m.blur_px = blur;
        m.speed_ratio = ratio;
        m.pixel_model = pixel;
        for (int c = 0; c < 3; ++c) {
          double white = m.ambient_electrons[static_cast<std::size_t>(c)];
          for (int k = 0; k < 3; ++k)
            white += m.crosstalk[static_cast<std::size_t>(c * 3 + k)] *
                     m.led_electrons[static_cast<std::size_t>(k)] * m.code.on_slots(k);
          EXPECT_NEAR(sum(channel_psf(m, c)), white, 1e-6 * white) << blur << " " << ratio;
        }
      }
}

/// The mean of sinc(j - d) over d in [a, b], by the midpoint rule.
double sinc_mean(int j, double a, double b) {
  const int nodes = 4000;
  double sum = 0;
  for (int q = 0; q < nodes; ++q) {
    const double x = 3.14159265358979323846 * (j - (a + (b - a) * (q + 0.5) / nodes));
    sum += x == 0 ? 1.0 : std::sin(x) / x;
  }
  return sum / nodes;
}

TEST(MotionPsf, BandLimitedSlotsAreTheSincsMeanFromALeadOfTaps) {
  EXPECT_EQ(pixel_model_lead(PixelModel::kBandLimited), kBandLimitedLead);
  EXPECT_EQ(pixel_model_lead(PixelModel::kBoxAperture), 0);
  // A still scene at a whole pixel: the identity, at tap `lead`.
  std::vector<double> still(pixel_model_taps(3, PixelModel::kBandLimited), 0.0);
  deposit_slot(still, 3, 0, 1, PixelModel::kBandLimited);
  for (std::size_t j = 0; j < still.size(); ++j)
    EXPECT_NEAR(still[j], j == 3 + kBandLimitedLead ? 1.0 : 0.0, 1e-12) << j;
  // A slot moving 0.3 .. 1.7 px: each tap the sinc's mean over the motion (the cut
  // tails' light shared out, a part in a thousand).
  std::vector<double> taps(pixel_model_taps(1.7, PixelModel::kBandLimited), 0.0);
  deposit_slot(taps, 0.3, 1.4, 1, PixelModel::kBandLimited);
  EXPECT_NEAR(sum(taps), 1.0, 1e-12);
  for (int j = -kBandLimitedLead; j <= 2 + kBandLimitedLead; ++j)
    EXPECT_NEAR(taps[static_cast<std::size_t>(j + kBandLimitedLead)], sinc_mean(j, 0.3, 1.7), 2e-3)
        << j;
  // One pixel per slot: the box's band-limited samples, not [0.5, 0.5]. Near Nyquist (0.4
  // cycles per pixel) they pass the box's sinc, 0.757; the box aperture's pair passes
  // cos(0.4 pi) = 0.309.
  std::vector<double> one(pixel_model_taps(1, PixelModel::kBandLimited), 0.0);
  deposit_slot(one, 0, 1, 1, PixelModel::kBandLimited);
  std::complex<double> response = 0;
  const double w = 0.8 * 3.14159265358979323846;
  for (std::size_t j = 0; j < one.size(); ++j)
    response += one[j] * std::polar(1.0, -w * static_cast<double>(j));
  EXPECT_NEAR(std::abs(response), std::sin(w / 2) / (w / 2), 0.01);
}

TEST(MotionPsf, UndoingTheLeadMovesTheLatentDownstream) {
  Plane latent(6, 2);
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 6; ++x) latent.at(x, y) = static_cast<float>(10 * y + x);
  undo_psf_lead(latent, 2);
  const float expected[] = {0, 0, 0, 1, 2, 3};
  for (int x = 0; x < 6; ++x) {
    EXPECT_EQ(latent.at(x, 0), expected[x]) << x;
    EXPECT_EQ(latent.at(x, 1), expected[x] + 10) << x;
  }
}

TEST(MotionPsf, BlockOffsetsMoveTheKnotsAndKeepTheTravel) {
  // 52 slots in 4 blocks: knots at slots 13, 26 and 39, linear between, 0 at the ends.
  auto edges = accelerating_slot_edges(52, 52, 1.0);
  const std::vector<double> offsets = {0.8, -0.4, 0.2};
  add_block_offsets(edges, offsets);
  EXPECT_NEAR(edges[0], 0, 1e-12);
  EXPECT_NEAR(edges[52], 52, 1e-12);
  EXPECT_NEAR(edges[13], 13.8, 1e-12);
  EXPECT_NEAR(edges[26], 25.6, 1e-12);
  EXPECT_NEAR(edges[39], 39.2, 1e-12);
  EXPECT_NEAR(edges[20], 20 + 0.8 + (7.0 / 13) * (-0.4 - 0.8), 1e-12);  // within block 1
  EXPECT_NEAR(edges[45], 45 + 0.2 * (7.0 / 13), 1e-12);                 // the last block
  // One offset per interior edge: each edge moved by its own offset.
  auto per_slot = accelerating_slot_edges(52, 52, 1.0);
  std::vector<double> each(51);
  for (std::size_t t = 0; t < each.size(); ++t) each[t] = 0.01 * static_cast<double>(t % 7);
  add_block_offsets(per_slot, each);
  for (std::size_t t = 1; t < 52; ++t) EXPECT_NEAR(per_slot[t], t + each[t - 1], 1e-12);
}

TEST(MotionPsf, BlockOffsetsOutsideTheModelAreRefused) {
  CaptureModel m;
  m.code = LedCode::parse("4242221144411121214241142422112112214412414144224412", 3).value();
  m.led_electrons = {1, 1, 1};
  m.block_offsets_px = {0.5, -0.5, 0.3};
  EXPECT_EQ(capture_model_problem(m), "");
  EXPECT_NEAR(slot_edges(m)[13], 13.5, 1e-12);
  CaptureModel steady = m;
  steady.block_offsets_px.clear();
  for (int c = 0; c < 3; ++c) {  // the light is the same; only where it lands moves
    EXPECT_NEAR(sum(channel_psf(m, c)), sum(channel_psf(steady, c)), 1e-9) << c;
    EXPECT_NE(channel_psf(m, c), channel_psf(steady, c)) << c;
  }
  m.block_offsets_px = {14.0, 0, 0};  // block 0 travels 27 px, block 1 goes back 1
  EXPECT_NE(capture_model_problem(m).find("backwards"), std::string::npos);
  m.block_offsets_px = {0.5, double{NAN}, 0};
  EXPECT_NE(capture_model_problem(m).find("finite"), std::string::npos);
  m.block_offsets_px.assign(52, 0.0);
  EXPECT_NE(capture_model_problem(m).find("fewer entries"), std::string::npos);
}

TEST(MotionPsf, SpeedRatioOutsideTheModelIsRefused) {
  CaptureModel m;
  m.code = LedCode::parse("124", 3).value();
  m.led_electrons = {1, 1, 1};
  for (double bad : {0.0, -1.0, 0.1, 6.0, double{NAN}, double{INFINITY}}) {
    m.speed_ratio = bad;
    EXPECT_NE(capture_model_problem(m).find("speed ratio"), std::string::npos) << bad;
  }
  m.speed_ratio = 1.5;
  EXPECT_EQ(capture_model_problem(m), "");
}

}  // namespace
}  // namespace flutterscan::imaging
