#pragma once
// The live view's HTTP server (docs/session.md, "Live view"), cpp-httplib on
// its own small thread pool at lowered priority:
//
//   GET /                    the page (live_view_page.hpp)
//   GET /state.json          LiveView::state()
//   GET /metrics             LiveView::metrics(), Prometheus text format
//   GET /frame/captured.jpg  the latest pictures (404 before the first); ?frame=N those of
//   GET /frame/fused.jpg     frame N while they are among the last three (else 404)
//   GET /files/NAME          a file of the session folder, whitelisted (session_file)
//
// Read-only: every other method is refused (405) and nothing here reaches
// the line. It binds where it is told; the caller warns when that is not loopback.

#include <atomic>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <thread>

#include "flutterscan/common/result.hpp"
#include "session/live_view.hpp"

namespace httplib {
class Server;
}

namespace flutterscan::session {

/// \brief The live view's address when --http is not given.
inline constexpr const char* kLiveViewDefaultHost = "127.0.0.1";
inline constexpr int kLiveViewDefaultPort = 8090;

struct HttpAddress {
  std::string host;
  int port = 0;  ///< 0: any free port
};

/// \brief "ADDR:PORT" ("[ADDR]:PORT" for IPv6), or "off" (none). The error says what is wrong.
Result<std::optional<HttpAddress>, std::string> parse_http_address(const std::string& text);

/// \brief Whether `host` is a loopback address or "localhost" (reachable from this machine only).
bool is_loopback(const std::string& host);

/// \brief The file of session folder `folder` that `name` (the path after
/// /files/, percent-decoded) may serve, or none: only summary.json,
/// report.html and the kept frames (frames/fNNNNNNNN.png, .fused.png), each a
/// regular file (no symlink) inside the folder.
std::optional<std::filesystem::path> session_file(const std::string& folder,
                                                  const std::string& name);

class LiveViewServer {
 public:
  explicit LiveViewServer(const LiveView& view);
  ~LiveViewServer();
  LiveViewServer(const LiveViewServer&) = delete;
  LiveViewServer& operator=(const LiveViewServer&) = delete;

  /// \brief Binds `address` and serves on its own threads; the error names the
  /// address and the cause (e.g. the port in use).
  std::string listen(const HttpAddress& address);
  /// \brief The port bound (0 before listen()).
  int port() const { return port_; }
  /// \brief Stops serving (also at destruction).
  void stop();

 private:
  const LiveView& view_;
  std::unique_ptr<httplib::Server> server_;
  std::thread thread_;
  std::atomic<bool> served_{false};  ///< the serving thread has returned
  int port_ = 0;
};

}  // namespace flutterscan::session
