#include "app/live_view_option.hpp"

#include <iostream>

#include "app/cli_errors.hpp"

namespace flutterscan::app {

void add_http_option(CLI::App* command, std::optional<std::string>& http) {
  command->add_option(
      "--http", http,
      "live view: a page of the running session, /state.json and Prometheus /metrics, "
      "read-only, at ADDR:PORT (default " +
          std::string(session::kLiveViewDefaultHost) + ":" +
          std::to_string(session::kLiveViewDefaultPort) +
          ", loopback only; port 0: any free one), or off");
}

bool start_live_view(const std::optional<std::string>& http, session::LiveViewServer& server) {
  const std::string text = http.value_or(std::string(session::kLiveViewDefaultHost) + ":" +
                                         std::to_string(session::kLiveViewDefaultPort));
  const auto address = session::parse_http_address(text);
  if (!address.ok()) throw UsageError(address.error());
  if (!address.value()) return false;
  const session::HttpAddress& at = *address.value();
  if (auto problem = server.listen(at); !problem.empty()) {
    if (http) throw UsageError(problem + " (--http ADDR:PORT picks another, --http off none)");
    std::cerr << "flutterscan: warning: " << problem
              << "; the session runs without it (--http ADDR:PORT picks another port)\n";
    return false;
  }
  const bool v6 = at.host.find(':') != std::string::npos;
  std::cerr << "flutterscan: live view on http://" << (v6 ? "[" + at.host + "]" : at.host) << ":"
            << server.port() << "/ (read-only)\n";
  if (!session::is_loopback(at.host))
    std::cerr << "flutterscan: warning: the live view listens on " << at.host
              << ": reachable from the network, without authentication (read-only)\n";
  return true;
}

}  // namespace flutterscan::app
