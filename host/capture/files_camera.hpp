#pragma once
// "files:DIR": replays a folder of frames, each an image file (8- or 16-bit
// PNG or TIFF, RGB or grey or an RGGB mosaic) with its capture descriptor
// beside it (same name, .json; docs/formats.md). Frames play in name order.
// An image without a descriptor (a ground truth, a fused output) is skipped.
// A descriptor's optional "capture" object gives the frame's camera sequence
// number and timestamp (`sequence`, `timestamp_ns`) and the labels' values
// (`truth`, `truth_in_view`) as a recorded session writes them; without it the
// frame index and 1/30 s steps stand in. The descriptor is read by
// imaging/capture_descriptor.hpp's reader: a field of the wrong type or range
// refuses the frame, naming the field and the file.

#include <memory>
#include <string>

#include "capture/camera_source.hpp"

namespace flutterscan::capture {

/// \brief A camera replaying the frames in `folder`.
std::unique_ptr<CameraSource> make_files_camera(const std::string& folder);

}  // namespace flutterscan::capture
