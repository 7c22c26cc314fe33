#include "session/live_view_server.hpp"

#include <arpa/inet.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <unistd.h>

#include <httplib.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <fstream>
#include <iterator>
#include <regex>

#include "session/live_view_page.hpp"

namespace flutterscan::session {

namespace {

namespace fs = std::filesystem;

constexpr int kServerThreads = 4;

/// httplib's pool, its threads below the workers: a page may wait, a frame may not.
class LowPriorityPool : public httplib::ThreadPool {
 public:
  using ThreadPool::ThreadPool;
  void enqueue(std::function<void()> fn) override {
    ThreadPool::enqueue([fn = std::move(fn)] {
      thread_local const bool lowered =
          setpriority(PRIO_PROCESS, static_cast<id_t>(gettid()), 10) == 0;
      (void)lowered;
      fn();
    });
  }
};

/// The page may run its own inline script and talk to this server only.
constexpr const char* kPagePolicy =
    "default-src 'none'; script-src 'unsafe-inline'; style-src 'unsafe-inline'; "
    "img-src 'self'; connect-src 'self'";
/// report.html: inline style and data-URI pictures, no script.
constexpr const char* kReportPolicy =
    "default-src 'none'; style-src 'unsafe-inline'; img-src data:";

std::string read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

bool regular_not_symlink(const fs::path& path) {
  std::error_code ec;
  return fs::symlink_status(path, ec).type() == fs::file_type::regular;
}

bool directory_not_symlink(const fs::path& path) {
  std::error_code ec;
  return fs::symlink_status(path, ec).type() == fs::file_type::directory;
}

}  // namespace

Result<std::optional<HttpAddress>, std::string> parse_http_address(const std::string& text) {
  using R = Result<std::optional<HttpAddress>, std::string>;
  if (text == "off") return R::success(std::nullopt);
  const std::string usage =
      "--http '" + text + "' must be ADDR:PORT (e.g. 127.0.0.1:8090, [::1]:8090) or off";
  const auto colon = text.rfind(':');
  if (colon == std::string::npos || colon == 0 || colon + 1 == text.size())
    return R::failure(usage);
  std::string host = text.substr(0, colon);
  if (host.front() == '[') {
    if (host.size() < 3 || host.back() != ']') return R::failure(usage);
    host = host.substr(1, host.size() - 2);
  } else if (host.find(':') != std::string::npos) {
    return R::failure(usage + ": an IPv6 address goes in brackets");
  }
  const std::string port_text = text.substr(colon + 1);
  if (port_text.size() > 5 || port_text.find_first_not_of("0123456789") != std::string::npos)
    return R::failure(usage + ": the port is a number 0..65535");
  const int port = std::stoi(port_text);
  if (port > 65535) return R::failure(usage + ": the port is a number 0..65535");
  return R::success(HttpAddress{host, port});
}

bool is_loopback(const std::string& host) {
  if (host == "localhost") return true;
  in_addr v4{};
  if (inet_pton(AF_INET, host.c_str(), &v4) == 1) return (ntohl(v4.s_addr) >> 24) == 127;
  in6_addr v6{};
  return inet_pton(AF_INET6, host.c_str(), &v6) == 1 && IN6_IS_ADDR_LOOPBACK(&v6);
}

std::optional<fs::path> session_file(const std::string& folder, const std::string& name) {
  static const std::regex allowed(
      R"((summary\.json|report\.html|frames/f[0-9]{8,20}(\.fused)?\.png))");
  if (folder.empty() || !std::regex_match(name, allowed)) return std::nullopt;
  const fs::path root(folder);
  const fs::path path = root / name;
  if (!directory_not_symlink(root) || !directory_not_symlink(path.parent_path()) ||
      !regular_not_symlink(path))
    return std::nullopt;
  // Inside the folder, whatever the folder's own path holds.
  std::error_code ec;
  const fs::path real_root = fs::canonical(root, ec);
  const fs::path real = fs::canonical(path, ec);
  if (ec || real.lexically_relative(real_root) != fs::path(name)) return std::nullopt;
  return path;
}

LiveViewServer::LiveViewServer(const LiveView& view)
    : view_(view), server_(std::make_unique<httplib::Server>()) {
  httplib::Server& s = *server_;
  s.new_task_queue = [] { return new LowPriorityPool(kServerThreads); };
  // SO_REUSEADDR only: httplib's default SO_REUSEPORT would let a second session bind the
  // same port and take every other request; this way a port in use is refused.
  s.set_socket_options([](int socket) {
    const int yes = 1;
    setsockopt(socket, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
  });
  // One request per connection: an idle browser connection never holds a thread.
  s.set_keep_alive_max_count(1);
  s.set_read_timeout(2);
  s.set_write_timeout(2);
  s.set_payload_max_length(4096);
  s.set_default_headers({{"Cache-Control", "no-store"}, {"X-Content-Type-Options", "nosniff"}});

  s.Get("/", [](const httplib::Request&, httplib::Response& res) {
    res.set_header("Content-Security-Policy", kPagePolicy);
    const std::string_view page = live_view_page();
    res.set_content(page.data(), page.size(), "text/html; charset=utf-8");
  });
  s.Get("/state.json", [this](const httplib::Request&, httplib::Response& res) {
    res.set_content(view_.state().dump(), "application/json");
  });
  s.Get("/metrics", [this](const httplib::Request&, httplib::Response& res) {
    res.set_content(view_.metrics(), "text/plain; version=0.0.4; charset=utf-8");
  });
  s.Get(R"(/frame/(captured|fused)\.jpg)", [this](const httplib::Request& req,
                                                  httplib::Response& res) {
    // ?frame=N: the pictures the page's state describes (the codes drawn over them).
    std::shared_ptr<const LivePicture> picture;
    if (!req.has_param("frame")) {
      picture = view_.picture();
    } else if (const std::string n = req.get_param_value("frame");
               !n.empty() && n.size() <= 19 &&
               n.find_first_not_of("0123456789") == std::string::npos) {
      picture = view_.picture_of(std::stoull(n));
    }
    if (!picture) {
      res.status = 404;
      res.set_content("no such picture (yet, or any longer)\n", "text/plain");
      return;
    }
    const auto& jpeg = req.matches[1] == "captured" ? picture->captured_jpeg : picture->fused_jpeg;
    res.set_content(reinterpret_cast<const char*>(jpeg.data()), jpeg.size(), "image/jpeg");
  });
  s.Get(R"(/files/(.*))", [this](const httplib::Request& req, httplib::Response& res) {
    const std::string name = req.matches[1];
    const auto path = session_file(view_.folder(), name);
    if (!path) {
      res.status = 404;
      res.set_content("not served\n", "text/plain");
      return;
    }
    const std::string ext = path->extension().string();
    if (ext == ".html") res.set_header("Content-Security-Policy", kReportPolicy);
    res.set_content(read_file(*path), ext == ".png"    ? "image/png"
                                      : ext == ".json" ? "application/json"
                                                       : "text/html; charset=utf-8");
  });
  // Read-only: nothing changes the line or the session.
  const auto refuse = [](const httplib::Request&, httplib::Response& res) {
    res.status = 405;
    res.set_header("Allow", "GET, HEAD");
    res.set_content("read-only: GET and HEAD only\n", "text/plain");
  };
  s.Post(".*", refuse);
  s.Put(".*", refuse);
  s.Patch(".*", refuse);
  s.Delete(".*", refuse);
  s.Options(".*", refuse);
}

LiveViewServer::~LiveViewServer() {
  stop();
}

std::string LiveViewServer::listen(const HttpAddress& address) {
  const std::string where = address.host + ":" + std::to_string(address.port);
  errno = 0;
  const int port = address.port == 0
                       ? server_->bind_to_any_port(address.host)
                       : (server_->bind_to_port(address.host, address.port) ? address.port : -1);
  if (port < 0) {
    const int cause = errno;
    return "live view: cannot listen on " + where + ": " +
           (cause == EADDRINUSE ? "the port is in use"
            : cause != 0        ? std::string(std::strerror(cause))
                                : std::string("the address is not available"));
  }
  port_ = port;
  thread_ = std::thread([this] {
    server_->listen_after_bind();
    served_ = true;
  });
  return {};
}

void LiveViewServer::stop() {
  if (!thread_.joinable()) return;
  // httplib's stop() does nothing until its loop has started.
  while (!server_->is_running() && !served_)
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  server_->stop();
  thread_.join();
}

}  // namespace flutterscan::session
