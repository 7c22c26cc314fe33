#pragma once
// Belt speed that varies within one exposure, as per-slot positions for
// imaging::segments_from_boundaries(): slot t covers [b[t], b[t + 1]) pixels.
// Both profiles keep the total motion at the nominal blur (what an encoder
// measures), so they isolate the effect of the non-uniform speed from a wrong
// blur length.

#include <cstdint>
#include <vector>

namespace flutterscan::sim {

/// \brief Belt jitter: slot t moves at the nominal speed times
/// (1 + rms n_t), n_t independent standard normals (speed floored at 0),
/// rescaled so the slots add up to `blur_px`. rms 0 gives t blur / L exactly.
std::vector<double> jittered_slot_boundaries(int slots, double blur_px, double rms,
                                             std::uint64_t seed);

/// \brief Constant acceleration: the speed ramps linearly from v (1 - a / 2)
/// at the start of the exposure to v (1 + a / 2) at its end (a =
/// `relative_change`, |a| <= 2), v = blur / exposure; boundaries are the exact
/// positions at the slot edges.
std::vector<double> accelerated_slot_boundaries(int slots, double blur_px, double relative_change);

}  // namespace flutterscan::sim
