#pragma once
// Results out, as a line on a belt uses them (docs/session.md, "Results
// protocol"): one JSON object per line, UTF-8, '\n'-terminated, over TCP
// (every connected client gets every line; the first line a client gets is
// the greeting {"protocol":"flutterscan-results","version":2}; read_record.hpp
// makes the lines) and optionally
// a serial port. Sending never blocks the pipeline: a client whose socket
// buffer is full is disconnected and counted; a serial port that cannot take
// a line loses it and counts it.

#include <atomic>
#include <cstdint>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace flutterscan::session {

class ResultsServer {
 public:
  ResultsServer() = default;
  ~ResultsServer();
  ResultsServer(const ResultsServer&) = delete;
  ResultsServer& operator=(const ResultsServer&) = delete;

  /// \brief Listens on bind_address:port (port 0: any free one, see port()).
  /// Error names the address and the cause.
  std::string listen(const std::string& bind_address, int port);
  /// \brief Opens a serial port (raw, 8N1, `baud`); error names the device.
  std::string open_serial(const std::string& device, int baud);
  /// \brief The TCP port listened on (0 if not listening).
  int port() const { return port_; }
  /// \brief Sends `line` (without '\n') to every client and the serial port.
  void publish(const std::string& line);
  /// \brief Stops accepting, closes every connection.
  void close();

  std::uint64_t lines_sent() const { return lines_sent_; }
  std::uint64_t clients_dropped() const { return clients_dropped_; }
  std::uint64_t serial_lines_lost() const { return serial_lines_lost_; }
  std::size_t clients() const;

 private:
  void accept_loop();
  bool send_all(int fd, const std::string& data);

  int listen_fd_ = -1;
  int serial_fd_ = -1;
  int port_ = 0;
  std::atomic<bool> stopping_{false};
  std::thread acceptor_;
  mutable std::mutex mutex_;
  std::vector<int> clients_;
  std::atomic<std::uint64_t> lines_sent_{0};
  std::atomic<std::uint64_t> clients_dropped_{0};
  std::atomic<std::uint64_t> serial_lines_lost_{0};
};

}  // namespace flutterscan::session
