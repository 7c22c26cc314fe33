#pragma once
// Writing a Cairo surface as a PNG without ever leaving a half-written file.

#include <cairo.h>

#include <string>

namespace flutterscan::plot {

/// \brief Writes `surface` as a PNG to a uniquely named temporary file beside
/// `path`, flushes it to disk and renames it over `path`. Returns "" on
/// success, else what failed (the temporary file is removed).
std::string write_surface_png(cairo_surface_t* surface, const std::string& path);

}  // namespace flutterscan::plot
