#pragma once
// Photo scenes for the simulator: a photograph of a real label (a carton, a
// product, a shipping label) as the object on the belt (docs/formats.md,
// "Photo scenes"). Each colour channel of the photo is the object's
// reflectance under one LED (red, green, blue: docs/conventions.md's LEDs 0,
// 1, 2); a grey photo gives three equal bands. Samples are sRGB-decoded to
// linear light (float files are taken as linear), then scaled into
// kPhotoBlack..kPhotoWhite. The photo keeps its own pixels (one photo pixel
// is one camera pixel, each a square of uniform reflectance), is turned by
// SceneSpec::rotate_deg about its centre and lies centred on a belt of
// SceneSpec::belt, with kMinBeltPx of belt on every side at least (less half a pixel where
// the frame's and the photo's sizes differ in parity); a frame too
// small for it is an error naming the size it needs.

#include <string>
#include <vector>

#include "flutterscan/common/result.hpp"
#include "imaging/image.hpp"
#include "sim/scene.hpp"

namespace flutterscan::sim {

/// \brief Reflectance of a photo's black (linear 0) and of its white (linear 1).
inline constexpr double kPhotoBlack = 0.04;
inline constexpr double kPhotoWhite = 0.90;

/// \brief Where a photo scene's photo lies and what it was.
struct PhotoLayout {
  int photo_width = 0;  ///< the photo's own size, pixels
  int photo_height = 0;
  bool grey = false;  ///< one channel, or three equal ones: the three bands are equal
  /// The turned photo's bounding box, camera pixels (rounded up).
  int box_width = 0;
  int box_height = 0;
  /// The photo's centre in the frame, camera pixel edges (pixel x covers [x, x + 1)).
  double centre_x = 0;
  double centre_y = 0;
};

/// \brief Where the photo of `spec` (a photo scene) lies in its spec.width x
/// spec.height frame. Errors: as render_photo_bands.
Result<PhotoLayout, std::string> photo_layout(const SceneSpec& spec);

/// \brief The smallest frame a photo scene fits in: its turned bounding box
/// and kMinBeltPx of belt on every side.
Result<std::pair<int, int>, std::string> photo_frame_size(const SceneSpec& spec);

/// \brief The reflectance of `spec` (a photo scene) under the red, green and
/// blue LEDs, `supersample` (1 to 16) times finer than spec.width x
/// spec.height. Errors: not a photo scene, a file that is missing or cannot be
/// decoded (the message names it), an angle that is not finite, a frame too
/// small for the turned photo, a belt reflectance outside 0..1.
Result<std::vector<imaging::Plane>, std::string> render_photo_bands(const SceneSpec& spec,
                                                                    int supersample = 1);

}  // namespace flutterscan::sim
