#pragma once
// The formula beside every measured speed of the datasheet (docs/datasheet.md,
// "The formula"): whether joint Wiener's latent still shows a label's finest
// alternation of modules above its noise, from the capture's own PSFs.
//
// A label's finest detail is one-module bars and spaces in turn: a square wave of
// period 2m pixels (m = module, px) and amplitude C / 2 (C = paper - ink). Its
// fundamental, at w_m = pi / m radians per pixel, has amplitude (2 / pi) C,
// times sinc(1 / 2m) for the pixel's box aperture (the latent is the scene
// averaged over each pixel). Joint Wiener passes it with the transfer
//   W(w) = S(w) / (S(w) + lambda P(w)),  S(w) = sum_c |G_c(w)|^2 / v_c
// (docs/conventions.md), and leaves per-pixel noise of variance
//   sigma^2 = mean over w of S(w) / (S(w) + lambda P(w))^2
// in reflectance. The reader gets the bars right while the fundamental clears
// the mid-level threshold by z noise sigmas, and every wider element (2 to 4
// modules, down to w_m / 4) comes through at least as well:
//   (2 / pi) C sinc(1 / 2m) min over w in [w_m / 4, w_m] of W(w) >= z sigma.
// Motion enters through G_c: the motion during one lit stretch (one slot of a
// coded exposure, the whole pulse of a strobe) is a box of that many pixels in
// every channel alike, whose zero at w_m (a box of 2m pixels) no code fills; so
// at high light the limit is v = 2 m p / t (p mm per pixel, t the lit stretch),
// and at low light sigma moves it lower. That is the noise limit. The formula is
// the lower of it and the decoder's resolution limit, lit_motion_speed() with
// lit_motion_modules(): one module during the lit stretch for Code 128, whose
// decoder measures widths (chosen after the first run: the 2-module limit
// over-predicted Code 128 by about 1.7 and Data Matrix by about 1.1). Belt
// jitter, the encoder's error and the reader's other tolerances are not in it:
// the measurement has them.

#include <functional>

#include "imaging/capture_model.hpp"
#include "sim/scene.hpp"

namespace flutterscan::bench {

/// \brief The noise margin the formula asks of the reader, in noise sigmas:
/// stated once, not fitted to the measurements.
inline constexpr double kReadMarginSigmas = 3.0;

/// \brief Print contrast of the simulated labels: paper 0.9 - ink 0.06.
inline constexpr double kLabelContrast = 0.84;

/// \brief The terms of the formula for one capture.
struct ReadMargin {
  double amplitude = 0;  ///< (2 / pi) C sinc(1 / 2m) transfer, reflectance
  double transfer = 0;   ///< min of W(w) over [w_m / 4, w_m]
  double noise = 0;      ///< sigma, reflectance rms per pixel
  /// amplitude - z sigma: >= 0 when the formula says the label reads.
  double margin(double z = kReadMarginSigmas) const { return amplitude - z * noise; }
};

/// \brief The formula's terms for `model` (its PSFs, noise and joint Wiener's
/// prior lambda = 1 / kLabelGradientVariance) and a module of `module_px`
/// pixels; channel noise taken at `mean_reflectance` of the white level.
ReadMargin read_margin(const imaging::CaptureModel& model, double module_px,
                       double contrast = kLabelContrast, double mean_reflectance = 0.6);

/// \brief sinc(x) = sin(pi x) / (pi x), 1 at 0.
double normalized_sinc(double x);

/// \brief The highest speed in [low, high] the formula reads at: the margin is
/// evaluated on a geometric grid (2% steps) from `low` to `high`, and the step
/// from the last grid speed that reads to the next is bisected to `precision`
/// (relative). The margin need not be monotonic: a coded exposure whose whole
/// blur is about two modules long is a plain box of that length, which loses the
/// finest bars at a slow belt that a faster one (the code spread over more
/// pixels) reads. Returns 0 when no speed reads, `high` when `high` does.
/// `model_at` gives the capture at a speed.
double formula_speed(const std::function<imaging::CaptureModel(double)>& model_at, double module_px,
                     double low, double high, double precision = 0.005,
                     double z = kReadMarginSigmas);

/// \brief How far the belt may move while the light is on without a break (one
/// slot of a coded exposure, the pulse of a strobe), in modules, for a decoder
/// of `kind`'s kind. Code 128's decoder measures every bar's and space's width
/// against its pattern table: a box blur of up to one module leaves every
/// element a point at full contrast and its mid-level crossings at the true
/// edges; beyond it the narrowest elements' widths depend on their neighbours
/// (1 module). A Data Matrix is sampled at module centres: the sign of the
/// finest alternation is enough, up to the box's zero (2 modules; the margin
/// above says where noise ends it first).
double lit_motion_modules(sim::SceneKind kind);

/// \brief The speed that moves the belt `modules` modules of `module_px` pixels
/// (`mm_per_px` mm each) in `lit_ms` milliseconds: the resolution limit
/// modules x module_px x mm_per_px / lit_ms.
double lit_motion_speed(double modules, double module_px, double mm_per_px, double lit_ms);

}  // namespace flutterscan::bench
