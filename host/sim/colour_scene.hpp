#pragma once
// Colour objects for the simulator: a label printed in a coloured ink on
// white paper, as one reflectance plane per LED band (docs/conventions.md: LED 0 red,
// 1 green, 2 blue). Paper and belt are grey (the same in every band); only
// the ink differs. The ink colours are typical magnitudes for process inks
// under narrow-band LEDs, not measurements: a red ink reflects most red light
// and little green or blue, a blue ink the reverse with some green.

#include <array>
#include <span>
#include <string>
#include <vector>

#include "flutterscan/common/result.hpp"
#include "imaging/image.hpp"
#include "sim/scene.hpp"

namespace flutterscan::sim {

/// \brief Reflectance of an ink under the red, green and blue LEDs.
using BandReflectance = std::array<double, 3>;

/// \brief Red print: light under the red LED, dark under green and blue.
inline constexpr BandReflectance kRedInk = {0.80, 0.08, 0.06};
/// \brief Blue print: light under the blue LED, dark under red, half-dark under green.
inline constexpr BandReflectance kBlueInk = {0.06, 0.20, 0.55};

/// \brief Renders `spec` (its layout, paper and belt) with the print in `ink`:
/// band k = paper or belt where there is no ink, ink[k] where there is, area
/// averaged at edges exactly as render_scene. Errors as render_scene, or an
/// ink reflectance outside 0..1.
Result<std::vector<imaging::Plane>, std::string> render_colour_scene(const SceneSpec& spec,
                                                                     const BandReflectance& ink);

/// \brief The grey image a colour scene is judged and decoded as: the mean of
/// its bands (equal weights; the three LEDs are budgeted alike).
imaging::Plane fuse_bands(std::span<const imaging::Plane> bands);

}  // namespace flutterscan::sim
