#pragma once
// The real-label photo set of the real-print benchmark: photos of real labels,
// each with NAME.txt beside it holding the exact text its code encodes, and
// the photo scene each becomes (sim/photo_scene.hpp).

#include <string>
#include <vector>

#include "flutterscan/common/result.hpp"
#include "imaging/image.hpp"
#include "sim/scene.hpp"

namespace flutterscan::bench {

struct RealPhoto {
  std::string name;  ///< the file name without its extension
  std::string path;
  std::string text;  ///< what the code encodes, byte for byte
};

/// \brief The photo files in `dir` (.png, .jpg, .jpeg, .tif, .tiff, any case),
/// with a .txt beside them or not, in name order; none where there is no folder.
std::vector<std::string> photo_files(const std::string& dir);

/// \brief The photos in `dir` (.png, .jpg, .jpeg, .tif, .tiff with a .txt
/// beside them), in name order, every `every`-th of those whose name contains
/// `match`. The error says why there are none (no folder, no photos).
Result<std::vector<RealPhoto>, std::string> real_photos(const std::string& dir, int every,
                                                        const std::string& match);

/// \brief The photo file at `path` as stored, as the reader sees an 8-bit grey
/// picture (reflectance 0..1): what the ceiling is read on.
imaging::Plane photo_file_grey(const std::string& path);

/// \brief The photo scene of `path` unturned, its frame sized as `flutterscan
/// simulate` sizes it for motion along x: the photo with sim::kMinBeltPx of belt
/// across and `blur_px` more along each side (the whole smear in view).
Result<sim::SceneSpec, std::string> photo_scene_spec(const std::string& path, double blur_px);

}  // namespace flutterscan::bench
