#pragma once
// Barcodes on a fused latent image (ZXing-C++), with where they are, and the
// label regions (bright paper on the darker belt) whether a code was read on
// them or not: a region without a decode is what becomes a NO-READ.

#include <string>
#include <vector>

#include "imaging/image.hpp"

namespace flutterscan::session {

/// \brief One decoded barcode.
struct DecodedCode {
  std::string text;
  std::string format;   ///< ZXing's name: "Code128", "EAN-13", "QRCode", "DataMatrix", ...
  double centre_x = 0;  ///< pixel column of the symbol's centre
  double centre_y = 0;
  double min_x = 0, max_x = 0;  ///< extent along x
};

/// \brief Every barcode ZXing reads on `latent` (reflectance, clipped to 0..1).
std::vector<DecodedCode> read_barcodes(const imaging::Plane& latent);

/// \brief A run of columns [begin, end) where the image is mostly label paper.
struct LabelRegion {
  int begin = 0;
  int end = 0;
};

/// \brief Label regions along x: columns where at least `min_fraction` of the
/// pixels are brighter than `paper_threshold`, in runs at least `min_width`
/// wide that touch neither edge (a label cut by the frame is not judged).
/// Dark gaps up to `max_gap` columns (the bars of a linear code) do not split a run.
std::vector<LabelRegion> find_label_regions(const imaging::Plane& latent,
                                            double paper_threshold = 0.62,
                                            double min_fraction = 0.05, int min_width = 48,
                                            int max_gap = 16);

}  // namespace flutterscan::session
