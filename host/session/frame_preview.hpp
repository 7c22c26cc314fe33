#pragma once
// The before/after pictures of report.html: a frame's DN planes stretched to
// 8 bits (display only: the brightest sample maps to white) and its fused
// latent, both at most 960 pixels wide, as PNG.

#include <cstdint>

#include "imaging/image.hpp"
#include "session/session_report.hpp"

namespace flutterscan::session {

/// \brief The preview of frame `sequence`: `dn` as captured (grey or RGB) and `fused` (0..1).
Preview make_preview(std::uint64_t sequence, const imaging::Image& dn, const imaging::Plane& fused);

}  // namespace flutterscan::session
