#include "session/results_server.hpp"

#include "session/read_record.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <termios.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cerrno>
#include <cstring>

namespace flutterscan::session {
namespace {

std::string greeting() {
  return nlohmann::json{{"protocol", "flutterscan-results"}, {"version", kResultsProtocolVersion}}
             .dump() +
         "\n";
}

speed_t baud_constant(int baud) {
  switch (baud) {
    case 9600:
      return B9600;
    case 19200:
      return B19200;
    case 38400:
      return B38400;
    case 57600:
      return B57600;
    case 115200:
      return B115200;
    case 230400:
      return B230400;
    case 460800:
      return B460800;
    case 921600:
      return B921600;
    default:
      return 0;
  }
}

}  // namespace

ResultsServer::~ResultsServer() {
  close();
}

std::string ResultsServer::listen(const std::string& bind_address, int port) {
  const std::string where = "results TCP " + bind_address + ":" + std::to_string(port);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(static_cast<std::uint16_t>(port));
  if (inet_pton(AF_INET, bind_address.c_str(), &address.sin_addr) != 1)
    return where + ": '" + bind_address + "' is not an IPv4 address";
  listen_fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (listen_fd_ < 0) return where + ": socket: " + std::strerror(errno);
  const int yes = 1;
  ::setsockopt(listen_fd_, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
  if (::bind(listen_fd_, reinterpret_cast<sockaddr*>(&address), sizeof address) != 0 ||
      ::listen(listen_fd_, 8) != 0) {
    const std::string cause = std::strerror(errno);
    ::close(listen_fd_);
    listen_fd_ = -1;
    return where + ": " + cause;
  }
  socklen_t length = sizeof address;
  ::getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&address), &length);
  port_ = ntohs(address.sin_port);
  stopping_ = false;
  acceptor_ = std::thread([this] { accept_loop(); });
  return {};
}

void ResultsServer::accept_loop() {
  while (!stopping_) {
    pollfd p{listen_fd_, POLLIN, 0};
    if (::poll(&p, 1, 100) <= 0) continue;
    const int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC | SOCK_NONBLOCK);
    if (fd < 0) continue;
    std::lock_guard lock(mutex_);
    if (send_all(fd, greeting()))
      clients_.push_back(fd);
    else
      ::close(fd);
  }
}

bool ResultsServer::send_all(int fd, const std::string& data) {
  std::size_t sent = 0;
  while (sent < data.size()) {
    const ssize_t n =
        ::send(fd, data.data() + sent, data.size() - sent, MSG_NOSIGNAL | MSG_DONTWAIT);
    if (n <= 0) return false;  // full buffer or gone: never wait
    sent += static_cast<std::size_t>(n);
  }
  return true;
}

std::string ResultsServer::open_serial(const std::string& device, int baud) {
  const speed_t speed = baud_constant(baud);
  if (speed == 0)
    return "results serial " + device + ": baud " + std::to_string(baud) + " not supported";
  serial_fd_ = ::open(device.c_str(), O_WRONLY | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (serial_fd_ < 0) return "results serial " + device + ": " + std::strerror(errno);
  termios tty{};
  if (::tcgetattr(serial_fd_, &tty) == 0) {
    ::cfmakeraw(&tty);
    ::cfsetospeed(&tty, speed);
    ::cfsetispeed(&tty, speed);
    ::tcsetattr(serial_fd_, TCSANOW, &tty);
  }
  return {};
}

void ResultsServer::publish(const std::string& line) {
  const std::string data = line + "\n";
  {
    std::lock_guard lock(mutex_);
    for (auto it = clients_.begin(); it != clients_.end();) {
      if (send_all(*it, data)) {
        ++it;
      } else {
        ::close(*it);
        it = clients_.erase(it);
        ++clients_dropped_;
      }
    }
  }
  if (serial_fd_ >= 0) {
    const ssize_t n = ::write(serial_fd_, data.data(), data.size());
    if (n != static_cast<ssize_t>(data.size())) ++serial_lines_lost_;
  }
  ++lines_sent_;
}

std::size_t ResultsServer::clients() const {
  std::lock_guard lock(mutex_);
  return clients_.size();
}

void ResultsServer::close() {
  stopping_ = true;
  if (acceptor_.joinable()) acceptor_.join();
  if (listen_fd_ >= 0) ::close(listen_fd_);
  listen_fd_ = -1;
  std::lock_guard lock(mutex_);
  for (int fd : clients_) {
    ::shutdown(fd, SHUT_RDWR);
    ::close(fd);
  }
  clients_.clear();
  if (serial_fd_ >= 0) ::close(serial_fd_);
  serial_fd_ = -1;
}

}  // namespace flutterscan::session
