#pragma once
// The live view's page (docs/session.md, "Live view"): one static HTML page
// with its style and script inline, no external resource. It asks the server
// for /state.json four times a second and shows the figures, the latest
// pictures (/frame/captured.jpg, /frame/fused.jpg, fetched again only when a
// newer frame was encoded) with the codes read drawn over the fused one, the
// guard flags, the latest objects and the recent NO-READs with their kept
// frames (/files/frames/...). Values read off labels are set as text, never
// as markup.

#include <string_view>

namespace flutterscan::session {

/// \brief The page's HTML.
std::string_view live_view_page();

}  // namespace flutterscan::session
