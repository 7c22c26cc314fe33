#pragma once
// Frame files: PNG and TIFF through OpenCV, JSON sidecars, and atomic writes
// (a temporary file in the same folder renamed over the target), so an
// existing output is never left half-written.

#include <nlohmann/json.hpp>

#include <string>

#include "flutterscan/common/result.hpp"
#include "imaging/image.hpp"

namespace flutterscan::app {

struct LoadedFrame {
  imaging::Image dn;       ///< planar, RGB order for colour files, values as stored
  int container_bits = 8;  ///< 8 or 16
};

/// \brief Reads an 8- or 16-bit grey or RGB PNG/TIFF. The error names the file and the problem.
Result<LoadedFrame, std::string> read_frame(const std::string& path);

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
