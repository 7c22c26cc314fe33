#pragma once
// What `flutterscan scan` and `flutterscan demo` share: running a session
// with a progress line on the terminal, Ctrl-C as a clean stop, and the
// closing summary.

#include "session/session_config.hpp"

namespace flutterscan::app {

/// \brief Runs `config`; prints progress (stderr) and the summary (stdout).
/// Throws UsageError (bad configuration) or RuntimeFailure (the session failed).
void run_session_command(session::SessionConfig config, bool progress);

}  // namespace flutterscan::app
