#pragma once
// What `flutterscan scan` and `flutterscan demo` share: running a session
// with a progress line on the terminal, Ctrl-C as a clean stop, the live view
// (--http, live_view_option.hpp), and the closing summary.

#include <optional>
#include <string>

#include "session/session_config.hpp"

namespace flutterscan::app {

/// \brief Runs `config` with the live view `http` asks for; prints progress
/// (stderr) and the summary (stdout). Throws UsageError (bad configuration)
/// or RuntimeFailure (the session failed).
void run_session_command(session::SessionConfig config, bool progress,
                         const std::optional<std::string>& http);

}  // namespace flutterscan::app
