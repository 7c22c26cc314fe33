#pragma once
// Frame files: PNG and TIFF through OpenCV, JSON sidecars, and atomic writes
// (a temporary file in the same folder renamed over the target), so an
// existing output is never left half-written.

#include <nlohmann/json.hpp>

#include <cstdint>
#include <span>
#include <string>
#include <utility>

#include "flutterscan/common/result.hpp"
#include "imaging/image.hpp"

namespace flutterscan::app {

struct LoadedFrame {
  imaging::Image dn;       ///< planar, RGB order for colour files, values as stored
  int container_bits = 8;  ///< 8 or 16
};

/// \brief Reads an 8- or 16-bit grey or RGB PNG/TIFF. The error names the file and the problem.
Result<LoadedFrame, std::string> read_frame(const std::string& path);

/// \brief The same from the file's bytes (`name` names them in errors). Only PNG
/// and TIFF are decoded, and only after their header's size is checked against
/// imaging::kMaxFrameSidePx and kMaxFramePixels (a 100-byte file must not make the
/// decoder allocate gigabytes).
Result<LoadedFrame, std::string> decode_frame(std::span<const std::uint8_t> bytes,
                                              const std::string& name);

/// \brief The width and height a PNG or TIFF header declares (the first image of a
/// TIFF); the error says why there is none (not PNG or TIFF, truncated header).
Result<std::pair<std::uint32_t, std::uint32_t>, std::string> declared_frame_size(
    std::span<const std::uint8_t> bytes);

/// \brief Writes planes (1 or 3) as a 16-bit PNG; values are rounded and clipped to 0..65535.
std::string write_png16(const std::string& path, const imaging::Image& image);

/// \brief Reads a JSON file; the error names the file and the line.
Result<nlohmann::json, std::string> read_json(const std::string& path);

/// \brief Writes text atomically; empty on success, else a message naming the path.
std::string write_text(const std::string& path, const std::string& text);

/// \brief `frame.png` -> `frame.json` (or `frame` + suffix + extension).
std::string sibling_path(const std::string& path, const std::string& suffix,
                         const std::string& extension);

}  // namespace flutterscan::app
