#pragma once
// `calibrate flat`: illumination and crosstalk vary across the field of view
// (an LED bar is brighter under its middle, its colours mix differently at the
// edges). The capture model's PSFs assume one LED-to-channel mixing A = M I
// (crosstalk times LED strength) for the whole frame.
//
// Physics: the LEDs light the scene in the camera's frame, so camera pixel n
// receives, from LED k, A_ck(n) times what a uniform light would give:
//   y_c(n) = sum_k A_ck(n) (h_k * x)(n) + noise.
// With A(n) known per pixel, C(n) = A_ref A(n)^-1 turns the frame into one
// seen under the uniform mixing A_ref, exactly (y' = C(n) y), so every method
// then deblurs it with the frame-wide model; noise changes only by C's
// deviation from identity (small when the light is nearly uniform).
//
// Measurement: from the same frames as `calibrate crosstalk` (a white target,
// every LED off, then each LED alone), A is measured per tile of a grid
// (median of each tile, black level removed). A_ref is the median over the
// tiles. Between tile centres C(n) is interpolated bilinearly.

#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <vector>

#include "flutterscan/common/result.hpp"
#include "imaging/image.hpp"

namespace flutterscan::imaging {

struct FlatField {
  int width = 0, height = 0;     ///< frame size measured on
  int tiles_x = 0, tiles_y = 0;  ///< grid
  int channels = 0, leds = 0;
  /// A per tile, row-major tiles (tile_y * tiles_x + tile_x), each channels x leds row-major, DN.
  std::vector<double> mixing;
  std::vector<double> reference;  ///< A_ref, channels x leds, DN
  double largest_deviation = 0;   ///< max over tiles and entries of |A / A_ref - 1| (diagonal)
};

/// \brief Measures the flat field from `dark` and `lit[k]` (LED k alone), DN, on a
/// tiles_x x tiles_y grid. Needs channels == LEDs (an invertible mixing per tile).
Result<FlatField, std::string> measure_flat_field(const Image& dark, std::span<const Image> lit,
                                                  int tiles_x, int tiles_y, double full_scale_dn);

/// \brief Applies C(n) = A_ref A(n)^-1 to `electrons` (black level removed) in place.
/// Fails when the frame's size or channels differ from the measurement's.
std::string apply_flat_field(Image& electrons, const FlatField& flat);

/// \brief The JSON file format (docs/formats.md: "flutterscan-flat-field", version 1).
nlohmann::json flat_field_to_json(const FlatField& flat);
/// \brief Reads it back; the error names the field.
Result<FlatField, std::string> flat_field_from_json(const nlohmann::json& json);

}  // namespace flutterscan::imaging
