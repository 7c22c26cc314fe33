#pragma once
// Reading one fused latent with a ReaderOptions bundle: the whole frame, or
// windows around the label paper found along the motion (decode_windows()).
// The one way the session, `deblur --decode` and the benches read codes.

#include <cstddef>
#include <optional>
#include <span>

#include "imaging/capture_model.hpp"
#include "imaging/image.hpp"
#include "reader/barcode_reader.hpp"
#include "reader/reader_options.hpp"

namespace flutterscan::reader {

/// \brief What reading one latent found.
struct CodeReading {
  BarcodeReadout readout;
  /// Area "labels": the windows read (0: no paper, nothing read); area "frame": none.
  std::optional<std::size_t> windows;
};

/// \brief The codes of `latent` (camera orientation) in `options.area`: the
/// whole frame, or the windows around `paper` (find_paper_runs on the latent
/// in the motion frame of `direction`; those cut by the frame's edge in
/// options.cut_window_views); with area "labels" and no paper, nothing is
/// read. Positions are the latent's.
CodeReading read_codes(const imaging::Plane& latent, std::span<const LabelRegion> paper,
                       imaging::Direction direction, const ReaderOptions& options);

}  // namespace flutterscan::reader
