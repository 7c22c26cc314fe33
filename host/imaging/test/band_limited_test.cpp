// The band-limited pixel model (motion_psf.hpp) on frames of the physics it
// names, rendered here without any of the project's PSF code: a band-limited
// scene (sums of sinusoids below Nyquist) moving continuously, each sinusoid
// through the code's continuous transform, as a peer simulator that moves a
// band-limited scene renders it. Told band-limited, the deblur restores the
// scene where it is (the PSFs' lead undone) and the residual guard sees a fit;
// told the default box aperture it fits the frame clearly worse.

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>
#include <random>

#include "imaging/capture_model.hpp"
#include "imaging/deblur.hpp"
#include "imaging/image.hpp"
#include "imaging/model_guards.hpp"
#include "imaging/motion_frame.hpp"

namespace flutterscan::imaging {
namespace {

constexpr int kWidth = 256, kHeight = 24, kBlur = 52;
constexpr double kWhite = 1e6;  // e- a white object gives over the exposure: shot noise 0.1%
constexpr double kReadNoise = 10;

const char* const kCode = "1010000111000001010000110011110111010111001001100111";  // Raskar's

/// The code's transform at w (radians per pixel) for one pixel of motion per
/// slot: each open slot a band-limited box, sum kWhite at w = 0.
std::complex<double> code_transform(double w) {
  const double sinc = w == 0 ? 1.0 : std::sin(w / 2) / (w / 2);
  std::complex<double> sum = 0;
  int open = 0;
  for (int t = 0; t < kBlur; ++t)
    if (kCode[t] == '1') sum += std::polar(1.0, -w * (t + 0.5)), ++open;
  return sum * sinc * kWhite / static_cast<double>(open);
}

struct Frames {
  Plane scene;  ///< reflectance
  Image frame;  ///< electrons, noisy
};

Frames render() {
  Frames out{Plane(kWidth, kHeight), Image{}};
  out.frame.channels.assign(1, Plane(kWidth, kHeight));
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unit(0, 1);
  std::normal_distribution<double> normal(0, 1);
  for (int y = 0; y < kHeight; ++y) {
    // Six sinusoids per row, up to 0.45 cycles per pixel: band-limited.
    double a[6], w[6], phase[6];
    for (int m = 0; m < 6; ++m) {
      a[m] = 0.04 + 0.04 * unit(rng);
      w[m] = 2 * std::numbers::pi * (0.02 + 0.43 * unit(rng));
      phase[m] = 2 * std::numbers::pi * unit(rng);
    }
    for (int x = 0; x < kWidth; ++x) {
      double r = 0.5;
      std::complex<double> e = 0.5 * code_transform(0);
      for (int m = 0; m < 6; ++m) {
        r += a[m] * std::cos(w[m] * x + phase[m]);
        e += a[m] * code_transform(w[m]) * std::polar(1.0, w[m] * x + phase[m]);
      }
      out.scene.at(x, y) = static_cast<float>(r);
      // Shot noise (Gaussian at these levels) and read noise.
      const double sigma = std::sqrt(std::max(0.0, e.real()) + kReadNoise * kReadNoise);
      out.frame.channels[0].at(x, y) = static_cast<float>(e.real() + sigma * normal(rng));
    }
  }
  return out;
}

CaptureModel told(PixelModel pixels) {
  CaptureModel m;
  m.code = LedCode::parse(kCode, 1).value();
  m.blur_px = kBlur;
  m.channels = 1;
  m.leds = 1;
  m.crosstalk = {1};
  m.ambient_electrons = {0};
  m.led_electrons = {kWhite / m.code.on_slots(0)};
  m.read_noise = kReadNoise;
  m.gain = 1;
  m.full_well = 4e6;
  m.bit_depth = 16;
  m.pixel_model = pixels;
  return m;
}

/// PSNR (peak 1) over the columns a blur length in from either side.
double interior_psnr(const Plane& truth, const Plane& latent) {
  double sum = 0;
  int count = 0;
  for (int y = 0; y < kHeight; ++y)
    for (int x = kBlur; x < kWidth - kBlur; ++x) {
      const double d = truth.at(x, y) - latent.at(x, y);
      sum += d * d;
      ++count;
    }
  return 10 * std::log10(count / sum);
}

TEST(BandLimitedPixels, TheDeblurToldSoRestoresABandLimitedSceneInPlace) {
  const auto f = render();
  const auto frame = MotionFrame::make(f.frame, Direction::kPlusX).value();
  double psnr[2], residual[2];
  int i = 0;
  for (PixelModel pixels : {PixelModel::kBandLimited, PixelModel::kBoxAperture}) {
    DeblurOptions options;
    options.method = Method::kJointWiener;
    const auto r = deblur(frame, told(pixels), options);
    ASSERT_TRUE(r.ok()) << r.error();
    psnr[i] = interior_psnr(f.scene, r.value().latent);
    residual[i] = residual_ratio(frame, r.value().latent, told(pixels), 1);
    ++i;
  }
  std::printf("band-limited: %.1f dB, residual %.2f; box aperture: %.1f dB, residual %.2f\n",
              psnr[0], residual[0], psnr[1], residual[1]);
  EXPECT_GT(psnr[0], 30);           // in place: a latent a pixel off would not reach this
  EXPECT_GT(psnr[0], psnr[1] + 1);  // the box aperture's PSFs vanish where this scene has detail
  EXPECT_LT(residual[0], 1.5);      // about the noise
  EXPECT_GT(residual[1], 2 * residual[0]);
}

TEST(BandLimitedPixels, ABayerMosaicIsRefused) {
  CaptureModel m = told(PixelModel::kBandLimited);
  m.channels = 3;
  m.leds = 3;
  m.crosstalk = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  m.ambient_electrons = {0, 0, 0};
  m.led_electrons = {1, 1, 1};
  m.code = LedCode::parse("124", 3).value();
  m.bayer_rggb = true;
  EXPECT_NE(capture_model_problem(m).find("band-limited"), std::string::npos);
  m.pixel_model = PixelModel::kBoxAperture;
  EXPECT_EQ(capture_model_problem(m), "");
}

}  // namespace
}  // namespace flutterscan::imaging
