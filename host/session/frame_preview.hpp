#pragma once
// The before/after pictures of report.html: a frame's DN planes stretched to
// 8 bits (display only: the brightest sample maps to white) and its fused
// latent, both at most 960 pixels wide, as PNG (exact, for the report) or
// JPEG (about a tenth of the CPU, for the live view's pictures twice a second).

#include <cstdint>

#include "imaging/image.hpp"
#include "session/session_report.hpp"

namespace flutterscan::session {

enum class PreviewEncoding { kPng, kJpeg };

/// \brief The preview of frame `sequence`: `dn` as captured (grey or RGB) and `fused` (0..1).
Preview make_preview(std::uint64_t sequence, const imaging::Image& dn, const imaging::Plane& fused,
                     PreviewEncoding encoding = PreviewEncoding::kPng);

}  // namespace flutterscan::session
