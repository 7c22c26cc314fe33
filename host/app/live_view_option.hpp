#pragma once
// `--http ADDR:PORT|off` of `flutterscan scan` and `flutterscan demo`: the
// session's live view (docs/session.md, "Live view"). Without the option it
// listens on 127.0.0.1:8090 and, when that port is taken, warns and lets the
// session run without it; an address asked for with --http that cannot be had
// is an error (exit 2) before the line is touched.

#include <CLI/CLI.hpp>

#include <optional>
#include <string>

#include "session/live_view.hpp"
#include "session/live_view_server.hpp"

namespace flutterscan::app {

/// \brief Adds --http to `command`, stored in `http` (unset: the default address).
void add_http_option(CLI::App* command, std::optional<std::string>& http);

/// \brief Starts `server` (serving its LiveView) as `http` says; says where on
/// stderr (and warns when it is reachable from the network). True when it
/// serves. Throws UsageError for a bad --http or an --http address it cannot have.
bool start_live_view(const std::optional<std::string>& http, session::LiveViewServer& server);

}  // namespace flutterscan::app
