#pragma once
// How a moving scene reaches the pixel grid (docs/algorithms.md, "Pixel model").
//
// The scene moves continuously while a slot is lit, and every pixel integrates
// the light over its square aperture. The model takes the latent image as
// piecewise constant on the pixels (each pixel's value is the scene's average
// over its square: what a sharp capture of it records) and the aperture as a
// box of one pixel. A pixel then sees the latent shifted by d pixels as
// (1 - f) x[i - n] + f x[i - n - 1] (n = floor(d), f = d - n): linear
// interpolation, whose kernel is the triangle tri(u) = max(0, 1 - |u|). A slot
// during which the scene moves from a to b pixels contributes its light spread
// over the taps as the average of tri(j - d) over d in [a, b]: at one pixel of
// motion per slot that is [0.5, 0.5] per slot, not one whole tap.
//
// PixelModel::kBandLimited takes the latent as the samples of a band-limited
// image instead (Shannon: sinc interpolation, what a peer simulator that
// moves a band-limited scene continuously assumes): a slot's light goes to
// tap j as the mean of sinc(j - d) over its motion, on both sides of it. Its
// PSFs start kBandLimitedLead taps before the motion does (the latent a
// method solves for with them is shifted by that much: undo_psf_lead()).
//
// PixelModel::kTapGrid keeps the older model that deposits each slot's box
// straight onto the taps (no aperture): only for comparisons with it.

#include <span>
#include <vector>

#include "imaging/image.hpp"

namespace flutterscan::imaging {

/// \brief How a slot's motion is laid onto the pixel grid.
enum class PixelModel {
  kBoxAperture,  ///< box pixel aperture over a pixel-wise constant latent (the default)
  kTapGrid,      ///< each slot's box deposited on whole taps (the model before the aperture)
  kBandLimited,  ///< a band-limited latent: each slot's box through sinc interpolation
};

/// \brief Taps a band-limited PSF carries on either side of the motion (the
/// sinc's tails beyond are cut, each slot's light kept whole).
inline constexpr int kBandLimitedLead = 12;

/// \brief How many taps a PSF of `model` has before the motion's start (tap
/// `lead` is displacement 0): kBandLimitedLead for kBandLimited, else 0.
int pixel_model_lead(PixelModel model);

/// \brief Moves `latent` (motion frame) `lead` pixels along the motion: the
/// latent a method solved for with PSFs that lead by that much, back where
/// displacement 0 puts it (the first `lead` columns repeat the first solved one).
void undo_psf_lead(Plane& latent, int lead);

/// \brief Adds the light `weight` of one slot, during which the scene moved
/// from `start_px` to `start_px + width_px` (>= 0), to `taps` (tap j: light a
/// white point deposits j - pixel_model_lead() pixels downstream). `taps` must hold
/// pixel_model_taps(start_px + width_px) entries, or the light past them is lost.
void deposit_slot(std::vector<double>& taps, double start_px, double width_px, double weight,
                  PixelModel model);

/// \brief Taps a PSF needs for motion up to `end_px` under `model`.
std::size_t pixel_model_taps(double end_px, PixelModel model);

/// \brief Object displacement (pixels) at the L + 1 slot edges of an exposure
/// that travels `blur_px` in total while the speed changes linearly in time
/// from v0 to v1 = speed_ratio x v0 (constant acceleration; 1 = constant
/// speed, edges at t blur / L). The displacement of slot t is quadratic in t.
std::vector<double> accelerating_slot_edges(int slots, double blur_px, double speed_ratio);

/// \brief Adds a wandering displacement to the L + 1 slot `edges`: the exposure
/// is split into offsets.size() + 1 blocks of equal time, the object is
/// offsets[i] pixels further than `edges` say at the end of block i (0 at the
/// exposure's start and end) and the offset changes linearly within a block: a
/// belt whose speed changes from block to block (jitter) with the same travel.
void add_block_offsets(std::vector<double>& edges, std::span<const double> offsets);

/// \brief Whether slot `edges` never decrease: the object never moves backwards.
bool edges_move_forward(std::span<const double> edges);

}  // namespace flutterscan::imaging
