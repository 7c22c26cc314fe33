#pragma once
// Results over MQTT (docs/session-output.md, "Results over MQTT"): each
// object's result line (read_record.hpp) as one message on results.mqtt.topic,
// and a retained status message on TOPIC/status: "running" with the counters
// (on every connect and at most once a second while results flow), "stopped"
// at the end, and "offline" as the client's will, which the broker publishes
// when the process dies or the connection is lost without a goodbye.
//
// The publisher's own thread runs libmosquitto's loop, so publish() never
// blocks the pipeline. A result waits in the client until the broker acknowledges it
// (QoS 1 and 2), across reconnects (1 s, doubling up to 30 s) while the broker
// is away, and is sent again after a reconnect if the broker had not
// acknowledged it. At most results.mqtt.queue_limit results wait: beyond it a
// result is dropped, logged and counted, never silently.

#include <nlohmann/json.hpp>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <unordered_set>

#include "session/session_config.hpp"

struct mosquitto;  // libmosquitto's client

namespace flutterscan::session {

/// \brief What the publisher did, for summary.json's results.mqtt.
struct MqttCounters {
  std::uint64_t published = 0;    ///< results the broker acknowledged (QoS 0: sent)
  std::uint64_t queued_max = 0;   ///< most results waiting for the broker at once
  std::uint64_t dropped = 0;      ///< results dropped: the queue full (QoS 0: the broker away)
  std::uint64_t reconnects = 0;   ///< connections after the first
  std::uint64_t undelivered = 0;  ///< results still waiting when the session stopped
};

class MqttPublisher {
 public:
  using Say = std::function<void(const std::string&)>;
  /// How long stop() waits for the broker to take the waiting results.
  static constexpr std::chrono::milliseconds kDrain{10000};

  MqttPublisher() = default;
  ~MqttPublisher();
  MqttPublisher(const MqttPublisher&) = delete;
  MqttPublisher& operator=(const MqttPublisher&) = delete;

  /// \brief Starts the client's thread and connects in the background (a broker
  /// not reachable yet is no error: results wait for it); `say` gets warnings
  /// and may be called from the client's thread. Error names what could not be set up.
  std::string start(const MqttConfig& config, Say say);
  /// \brief Queues `line` as one message on the topic; never blocks.
  void publish(const std::string& line);
  /// \brief Waits up to `drain` for the broker to take the waiting results,
  /// publishes the "stopped" status and disconnects.
  void stop(std::chrono::milliseconds drain = kDrain);

  MqttCounters counters() const;
  /// \brief The broker, topic, QoS and counters, as summary.json's results.mqtt.
  nlohmann::json summary() const;

 private:
  /// The client's thread: libmosquitto's loop, and after any failure (the broker
  /// not there at the start, lost, a TLS or name lookup error) a new connection
  /// after 1 s, doubling up to 30 s, until stop().
  void run(int first_connect);
  static void on_connect(mosquitto* client, void* self, int rc);
  static void on_disconnect(mosquitto* client, void* self, int rc);
  static void on_publish(mosquitto* client, void* self, int mid);
  /// libmosquitto's errors and warnings (a TLS handshake refused, say), each text once in a row.
  static void on_log(mosquitto* client, void* self, int level, const char* text);
  /// The status message ("running" or "stopped") with the counters; mutex_ held.
  void publish_status_locked(const char* state);
  nlohmann::json status_locked(const char* state) const;

  MqttConfig config_;
  Say say_;
  std::string status_topic_;
  std::string broker_;  ///< "mqtt://host:port", for messages
  mosquitto* client_ = nullptr;
  std::thread thread_;    ///< the client's thread (run)
  bool running_ = false;  ///< the client's thread started
  std::atomic<bool> stopping_{false};
  std::atomic<bool> connected_since_failure_{false};  ///< the backoff starts again at 1 s

  mutable std::mutex mutex_;
  std::condition_variable acknowledged_;
  std::unordered_set<int> waiting_;  ///< message ids of results not yet acknowledged
  std::unordered_set<int> status_ids_;
  MqttCounters counters_;
  bool connected_ = false;
  std::uint64_t connects_ = 0;
  int last_refusal_ = 0;
  /// Not mutex_: libmosquitto calls on_log holding its own lock, which
  /// mosquitto_publish (called with mutex_ held) takes too. No other lock is
  /// taken while it is held.
  std::mutex log_mutex_;
  std::string last_log_;
  bool told_waiting_ = false;  ///< said that results wait for the broker, since the last connect
  bool overflowing_ = false;
  std::uint64_t dropped_in_overflow_ = 0;
  std::chrono::steady_clock::time_point last_status_{};
};

}  // namespace flutterscan::session
