#include "session/mqtt_publisher.hpp"

#include <mosquitto.h>

#include <algorithm>
#include <chrono>
#include <mutex>
#include <thread>

#include "session/read_record.hpp"

namespace flutterscan::session {
namespace {

constexpr int kKeepaliveS = 10;
constexpr std::chrono::seconds kReconnectMin{1}, kReconnectMax{30};

std::string utc_now() {
  return iso8601_utc(std::chrono::duration_cast<std::chrono::milliseconds>(
                         std::chrono::system_clock::now().time_since_epoch())
                         .count());
}

}  // namespace

MqttPublisher::~MqttPublisher() {
  if (running_) stop(std::chrono::milliseconds(0));
  if (client_ != nullptr) mosquitto_destroy(client_);
}

std::string MqttPublisher::start(const MqttConfig& config, Say say) {
  static std::once_flag library;
  std::call_once(library, [] { mosquitto_lib_init(); });
  config_ = config;
  say_ = std::move(say);
  status_topic_ = config_.topic + "/status";
  broker_ = std::string(config_.tls ? "mqtts://" : "mqtt://") + config_.host + ":" +
            std::to_string(config_.port);
  const auto failed = [&](const std::string& what, int rc) {
    return "results.mqtt: " + what + ": " + mosquitto_strerror(rc);
  };
  client_ = mosquitto_new(config_.client_id.c_str(), true, this);
  if (client_ == nullptr) return "results.mqtt: cannot make the MQTT client";
  mosquitto_connect_callback_set(client_, on_connect);
  mosquitto_disconnect_callback_set(client_, on_disconnect);
  mosquitto_publish_callback_set(client_, on_publish);
  mosquitto_log_callback_set(client_, on_log);
  // Publishing from the session's threads while the client's thread runs the loop.
  mosquitto_threaded_set(client_, true);
  mosquitto_int_option(client_, MOSQ_OPT_TCP_NODELAY, 1);  // a result goes out at once
  if (!config_.username.empty())
    if (int rc = mosquitto_username_pw_set(
            client_, config_.username.c_str(),
            config_.password.empty() ? nullptr : config_.password.c_str());
        rc != MOSQ_ERR_SUCCESS)
      return failed("username", rc);
  if (config_.tls) {
    const auto or_null = [](const std::string& s) { return s.empty() ? nullptr : s.c_str(); };
    if (int rc = mosquitto_tls_set(client_, or_null(config_.ca_file),
                                   config_.ca_file.empty() ? "/etc/ssl/certs" : nullptr,
                                   or_null(config_.cert_file), or_null(config_.key_file), nullptr);
        rc != MOSQ_ERR_SUCCESS)
      return failed("TLS files", rc);
  }
  const std::string will =
      nlohmann::json{{"state", "offline"}, {"client_id", config_.client_id}}.dump();
  if (int rc = mosquitto_will_set(client_, status_topic_.c_str(), static_cast<int>(will.size()),
                                  will.data(), 1, true);
      rc != MOSQ_ERR_SUCCESS)
    return failed("will on " + status_topic_, rc);
  // A broker not there yet is tried again by the client's thread, like a lost one.
  const int connected =
      mosquitto_connect_async(client_, config_.host.c_str(), config_.port, kKeepaliveS);
  if (connected == MOSQ_ERR_INVAL || connected == MOSQ_ERR_NOMEM)
    return failed("broker " + broker_, connected);
  told_waiting_ = connected != MOSQ_ERR_SUCCESS;
  if (told_waiting_ && say_)
    say_("warning: MQTT broker " + broker_ + " not reachable yet (" +
         mosquitto_strerror(connected) +
         "): results wait for it (up to results.mqtt.queue_limit = " +
         std::to_string(config_.queue_limit) + ")");
  thread_ = std::thread([this, connected] { run(connected); });
  running_ = true;
  return {};
}

void MqttPublisher::publish(const std::string& line) {
  std::lock_guard lock(mutex_);
  if (waiting_.size() >= config_.queue_limit) {
    ++counters_.dropped;
    ++dropped_in_overflow_;
    if (!overflowing_ && say_)
      say_("warning: MQTT: " + std::to_string(waiting_.size()) +
           " results wait for the broker (results.mqtt.queue_limit): results are dropped "
           "until it takes them, each counted (summary.json results.mqtt.dropped)");
    overflowing_ = true;
    return;
  }
  if (overflowing_ && say_)
    say_("MQTT: the broker takes results again; " + std::to_string(dropped_in_overflow_) +
         " dropped meanwhile");
  overflowing_ = false;
  dropped_in_overflow_ = 0;
  if (!connected_ && !told_waiting_ && say_)
    say_("warning: MQTT broker " + broker_ +
         " not connected: results wait for it (up to results.mqtt.queue_limit = " +
         std::to_string(config_.queue_limit) + ")");
  told_waiting_ = told_waiting_ || !connected_;
  int mid = 0;
  // The lock is held across the call so that the acknowledgement (on the
  // client's thread) finds the id. With QoS 1 and 2 libmosquitto keeps the
  // message while not connected (returning MOSQ_ERR_NO_CONN) and sends it once
  // connected; a QoS 0 message is lost then.
  const int rc = mosquitto_publish(client_, &mid, config_.topic.c_str(),
                                   static_cast<int>(line.size()), line.data(), config_.qos, false);
  if (rc == MOSQ_ERR_SUCCESS || (rc == MOSQ_ERR_NO_CONN && config_.qos > 0)) {
    waiting_.insert(mid);
    counters_.queued_max = std::max<std::uint64_t>(counters_.queued_max, waiting_.size());
  } else {
    ++counters_.dropped;
    if (say_)
      say_(std::string("warning: MQTT: a result was dropped (") + mosquitto_strerror(rc) +
           "), counted in summary.json results.mqtt.dropped");
  }
  const auto now = std::chrono::steady_clock::now();
  if (connected_ && now - last_status_ >= std::chrono::seconds(1)) publish_status_locked("running");
}

void MqttPublisher::stop(std::chrono::milliseconds drain) {
  if (!running_) return;
  running_ = false;
  std::unique_lock lock(mutex_);
  acknowledged_.wait_for(lock, drain, [&] { return waiting_.empty(); });
  counters_.undelivered = waiting_.size();
  if (counters_.undelivered > 0 && say_)
    say_("warning: MQTT: " + std::to_string(counters_.undelivered) +
         " results were not acknowledged by the broker " + broker_ + " when the session stopped");
  if (connected_) {
    publish_status_locked("stopped");
    acknowledged_.wait_for(lock, std::chrono::seconds(2), [&] { return status_ids_.empty(); });
  }
  lock.unlock();
  mosquitto_disconnect(client_);  // the client's thread sends it, then ends
  {
    std::lock_guard stopping_lock(mutex_);  // run() waits for it under the lock
    stopping_ = true;
  }
  acknowledged_.notify_all();
  thread_.join();
}

void MqttPublisher::run(int first_connect) {
  int rc = first_connect;
  auto delay = kReconnectMin;
  std::chrono::steady_clock::time_point give_up{};
  while (true) {
    if (rc == MOSQ_ERR_SUCCESS) rc = mosquitto_loop(client_, 100, 1);
    if (stopping_) {
      // Stopping: the loop goes on until the DISCONNECT is out and the
      // connection closed, 2 s at most.
      const auto now = std::chrono::steady_clock::now();
      if (give_up == std::chrono::steady_clock::time_point{})
        give_up = now + std::chrono::seconds(2);
      if (rc != MOSQ_ERR_SUCCESS || now > give_up) return;
      continue;
    }
    if (rc == MOSQ_ERR_SUCCESS) continue;
    // Not connected: again after the delay (1 s after a connection that worked,
    // doubling up to 30 s while none does).
    if (connected_since_failure_.exchange(false)) delay = kReconnectMin;
    {
      std::unique_lock lock(mutex_);
      acknowledged_.wait_for(lock, delay, [&] { return stopping_.load(); });
    }
    if (stopping_) return;
    delay = std::min(delay * 2, kReconnectMax);
    rc = mosquitto_reconnect_async(client_);
  }
}

MqttCounters MqttPublisher::counters() const {
  std::lock_guard lock(mutex_);
  return counters_;
}

nlohmann::json MqttPublisher::summary() const {
  const MqttCounters c = counters();
  return {{"broker", broker_},          {"topic", config_.topic},      {"qos", config_.qos},
          {"published", c.published},   {"queued_max", c.queued_max},  {"dropped", c.dropped},
          {"reconnects", c.reconnects}, {"undelivered", c.undelivered}};
}

nlohmann::json MqttPublisher::status_locked(const char* state) const {
  return {{"state", state},
          {"client_id", config_.client_id},
          {"time", utc_now()},
          {"published", counters_.published},
          {"waiting", waiting_.size()},
          {"queued_max", counters_.queued_max},
          {"dropped", counters_.dropped},
          {"reconnects", counters_.reconnects}};
}

void MqttPublisher::publish_status_locked(const char* state) {
  last_status_ = std::chrono::steady_clock::now();
  const std::string status = status_locked(state).dump();
  int mid = 0;
  if (mosquitto_publish(client_, &mid, status_topic_.c_str(), static_cast<int>(status.size()),
                        status.data(), 1, true) == MOSQ_ERR_SUCCESS)
    status_ids_.insert(mid);
}

void MqttPublisher::on_connect(mosquitto*, void* self, int rc) {
  auto& p = *static_cast<MqttPublisher*>(self);
  std::lock_guard lock(p.mutex_);
  if (rc != 0) {  // refused (a wrong password, say): the client tries again
    if (rc != p.last_refusal_ && p.say_)
      p.say_("warning: MQTT broker " + p.broker_ +
             " refused the connection: " + mosquitto_connack_string(rc));
    p.last_refusal_ = rc;
    return;
  }
  p.last_refusal_ = 0;
  p.told_waiting_ = false;
  p.connected_since_failure_ = true;
  {
    std::lock_guard log_lock(p.log_mutex_);  // the next trouble is told again
    p.last_log_.clear();
  }
  p.connected_ = true;
  if (p.connects_++ > 0) {
    ++p.counters_.reconnects;
    if (p.say_)
      p.say_("MQTT: connected to " + p.broker_ + " again; " + std::to_string(p.waiting_.size()) +
             " results waiting");
  }
  p.publish_status_locked("running");
}

void MqttPublisher::on_disconnect(mosquitto*, void* self, int rc) {
  auto& p = *static_cast<MqttPublisher*>(self);
  std::lock_guard lock(p.mutex_);
  const bool was_connected = p.connected_;
  p.connected_ = false;
  // Unacknowledged status messages go again with the next "running" one.
  p.status_ids_.clear();
  p.acknowledged_.notify_all();
  if (rc != 0 && was_connected && p.say_)
    p.say_("warning: MQTT broker " + p.broker_ +
           " lost: reconnecting; results wait for it (up to results.mqtt.queue_limit = " +
           std::to_string(p.config_.queue_limit) + ")");
  p.told_waiting_ = p.told_waiting_ || (rc != 0 && was_connected);
}

void MqttPublisher::on_log(mosquitto*, void* self, int level, const char* text) {
  if ((level & (MOSQ_LOG_ERR | MOSQ_LOG_WARNING)) == 0) return;
  auto& p = *static_cast<MqttPublisher*>(self);
  std::lock_guard lock(p.log_mutex_);
  if (text == p.last_log_) return;
  p.last_log_ = text;
  if (p.say_) p.say_("warning: MQTT: " + p.last_log_);
}

void MqttPublisher::on_publish(mosquitto*, void* self, int mid) {
  auto& p = *static_cast<MqttPublisher*>(self);
  std::lock_guard lock(p.mutex_);
  if (p.waiting_.erase(mid) > 0)
    ++p.counters_.published;
  else
    p.status_ids_.erase(mid);
  p.acknowledged_.notify_all();
}

}  // namespace flutterscan::session
