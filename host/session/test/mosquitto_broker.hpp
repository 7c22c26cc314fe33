#pragma once
// A real mosquitto broker for the MQTT tests and benchmark: on a free loopback
// port, its persistence (the subscribers' sessions and their queued messages)
// in its folder, so that a restart on the same port keeps them; and the
// programs it comes with, run as child processes.

#include <arpa/inet.h>
#include <netinet/in.h>
#include <pwd.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

namespace flutterscan::session::testing {

/// \brief Starts `args` (args[0] the program's path) with stdout to `out` and stderr to
/// `err`; its pid, or -1.
inline pid_t spawn_program(const std::vector<std::string>& args, const std::filesystem::path& out,
                           const std::filesystem::path& err) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    if (!std::freopen(out.c_str(), "w", stdout) || !std::freopen(err.c_str(), "w", stderr))
      _exit(126);
    std::vector<std::string> copies = args;
    std::vector<char*> argv;
    for (auto& a : copies) argv.push_back(a.data());
    argv.push_back(nullptr);
    ::execv(argv[0], argv.data());
    _exit(127);
  }
  return pid;
}

/// \brief Waits for `pid`; its exit code, or 128 + the signal that ended it.
inline int wait_program(pid_t pid) {
  int status = 0;
  if (::waitpid(pid, &status, 0) != pid) return -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

/// \brief A TCP port free on 127.0.0.1 a moment ago.
inline int free_loopback_port() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t length = sizeof address;
  int port = -1;
  if (::bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) == 0 &&
      ::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length) == 0)
    port = ntohs(address.sin_port);
  ::close(fd);
  return port;
}

/// \brief True once something accepts connections on 127.0.0.1:`port`.
inline bool accepts(int port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(static_cast<std::uint16_t>(port));
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  const bool ok = ::connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) == 0;
  ::close(fd);
  return ok;
}

/// \brief What a test broker asks of its clients besides the defaults.
struct BrokerOptions {
  /// Made by mosquitto_passwd; empty: anyone may connect.
  std::filesystem::path password_file;
  /// TLS on the listener: its certificate and key (empty: plain TCP).
  std::filesystem::path certificate, key;
};

class MosquittoBroker {
 public:
  /// \brief A broker run from `binary` with its config, log and persistence in `dir`.
  MosquittoBroker(std::string binary, std::filesystem::path dir, const BrokerOptions& options = {})
      : binary_(std::move(binary)), dir_(std::move(dir)), port_(free_loopback_port()) {
    std::ofstream conf(dir_ / "mosquitto.conf");
    conf << "listener " << port_ << " 127.0.0.1\n";
    if (!options.certificate.empty())
      conf << "certfile " << options.certificate.string() << "\nkeyfile " << options.key.string()
           << "\n";
    if (options.password_file.empty())
      conf << "allow_anonymous true\n";
    else
      conf << "allow_anonymous false\npassword_file " << options.password_file.string() << "\n";
    conf << "set_tcp_nodelay true\n"
         << "persistence true\n"
         << "persistence_location " << (dir_ / "").string() << "\n"
         << "log_dest file " << (dir_ / "broker.log").string() << "\n";
    // Run as root, mosquitto would become user mosquitto, who cannot write the folder.
    if (const passwd* user = ::getpwuid(::getuid())) conf << "user " << user->pw_name << "\n";
  }
  ~MosquittoBroker() { stop(); }
  MosquittoBroker(const MosquittoBroker&) = delete;
  MosquittoBroker& operator=(const MosquittoBroker&) = delete;

  int port() const { return port_; }
  std::string url() const { return "mqtt://127.0.0.1:" + std::to_string(port_); }

  /// \brief Starts it and waits (10 s at most) until it accepts connections; false if it did not.
  bool start() {
    pid_ = spawn_program({binary_, "-c", (dir_ / "mosquitto.conf").string()}, dir_ / "stdout",
                         dir_ / "stderr");
    for (int i = 0; i < 200 && pid_ > 0; ++i) {
      if (accepts(port_)) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    return false;
  }
  /// \brief SIGTERM: it saves its persistence and ends.
  void stop() {
    if (pid_ <= 0) return;
    ::kill(pid_, SIGTERM);
    wait_program(pid_);
    pid_ = -1;
  }

 private:
  std::string binary_;
  std::filesystem::path dir_;
  int port_;
  pid_t pid_ = -1;
};

}  // namespace flutterscan::session::testing
