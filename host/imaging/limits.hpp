#pragma once
// The largest sizes the imaging code accepts: every parameter that becomes an
// allocation or a loop count is checked against these where it enters
// (session config, capture descriptors, capture models), so that a mistyped
// value is refused with its name instead of reaching an allocation.

namespace flutterscan::imaging {

/// The longest motion blur a capture model may have, in pixels (the PSF, the
/// consistency cost and the padded rows all grow with it). A real line's blur
/// is tens to a few hundred pixels; a blur must also be shorter than the image
/// along the motion, which each function checks against its own image.
inline constexpr double kMaxBlurPx = 4096;

/// The longest side of a frame the host takes from a camera or a file, pixels.
inline constexpr int kMaxFrameSidePx = 16384;

/// The most pixels of one frame (a 64-megapixel sensor).
inline constexpr long long kMaxFramePixels = 64LL << 20;

/// The largest crosstalk entry (a camera channel's response to an LED relative to
/// its own, about 0..1 in practice).
inline constexpr double kMaxCrosstalk = 1000;

/// The smallest crosstalk entry other than 0: below it a channel's response is
/// nothing a camera can measure, and its powers underflow in the deconvolutions
/// (1 / 1e-318 is infinite).
inline constexpr double kMinCrosstalk = 1e-9;

/// The largest magnitude of a pixel the deconvolutions take (electrons or DN).
inline constexpr float kMaxPixelValue = 1e15f;

/// The least light per slot of an LED that is on (below it the PSF's taps
/// vanish in float and the deconvolution divides by nothing).
inline constexpr double kMinLitElectrons = 1e-3;

/// The most electrons per slot (LED) or per exposure (ambient) a model may say.
inline constexpr double kMaxModelElectrons = 1e9;

}  // namespace flutterscan::imaging
