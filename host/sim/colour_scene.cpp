#include "sim/colour_scene.hpp"

#include <cmath>

namespace flutterscan::sim {

Result<std::vector<imaging::Plane>, std::string> render_colour_scene(const SceneSpec& spec,
                                                                     const BandReflectance& ink) {
  using Out = Result<std::vector<imaging::Plane>, std::string>;
  for (double v : ink)
    if (!std::isfinite(v) || v < 0 || v > 1)
      return Out::failure("colour scene: ink reflectance " + std::to_string(v) +
                          " is outside 0..1");
  // Ink coverage: the layout with white paper and belt and black ink.
  SceneSpec cover_spec = spec;
  cover_spec.paper = 1;
  cover_spec.belt = 1;
  cover_spec.ink = 0;
  cover_spec.texture = 0;
  auto cover = render_scene(cover_spec);
  if (!cover.ok()) return Out::failure(cover.error());
  // Paper and belt without print (texture, if any, stays on the paper).
  SceneSpec base_spec = spec;
  base_spec.ink = spec.paper;
  auto base = render_scene(base_spec);
  if (!base.ok()) return Out::failure(base.error());
  std::vector<imaging::Plane> bands;
  for (double band_ink : ink) {
    imaging::Plane band(spec.width, spec.height);
    for (std::size_t i = 0; i < band.pixels.size(); ++i) {
      const double covered = 1.0 - cover.value().pixels[i];
      band.pixels[i] =
          static_cast<float>(base.value().pixels[i] * (1.0 - covered) + band_ink * covered);
    }
    bands.push_back(std::move(band));
  }
  return Out::success(std::move(bands));
}

imaging::Plane fuse_bands(std::span<const imaging::Plane> bands) {
  if (bands.empty()) return {};
  imaging::Plane grey(bands[0].width, bands[0].height);
  for (const auto& band : bands)
    for (std::size_t i = 0; i < grey.pixels.size(); ++i) grey.pixels[i] += band.pixels[i];
  const auto n = static_cast<float>(bands.size());
  for (float& v : grey.pixels) v /= n;
  return grey;
}

}  // namespace flutterscan::sim
