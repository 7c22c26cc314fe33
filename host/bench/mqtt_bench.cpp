// mqtt_bench: delivery latency of results over MQTT on loopback. A real
// mosquitto broker on a free port, the session's MqttPublisher publishing
// result lines the size of a READ object's record at a steady rate, and a
// libmosquitto subscriber timing each arrival: from the publish() call to the
// message in the subscriber's callback, p50, p99 and max, QoS 1 and QoS 0 side
// by side in one run. Not a test: `tools/bench` (BENCH_ONLY=mqtt) runs it;
// docs/benchmarks.md quotes it.
//
//   mqtt_bench [--messages N] [--interval-us U]

#include <mosquitto.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "session/mqtt_publisher.hpp"
#include "session/test/mosquitto_broker.hpp"
#include "session/value_distribution.hpp"

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using flutterscan::session::MqttConfig;
using flutterscan::session::MqttPublisher;

/// A READ object's result line (docs/session-output.md's example), numbered `object`.
std::string result_line(std::size_t object) {
  return "{\"object\":" + std::to_string(object) +
         ",\"belt_px\":-3612.5,\"first_frame\":21,\"last_frame\":23,\"frames\":3,"
         "\"decoded_frames\":3,\"status\":\"READ\",\"value\":\"FS-00006\",\"format\":"
         "\"Code128\",\"time\":\"2026-11-25T17:41:02.317Z\",\"sequence\":22,\"camera_ns\":"
         "1366702214,\"trigger\":{\"exposure_counter\":23,\"encoder_delta\":240,\"travel_px\":"
         "3960.0},\"blur_px\":60.0,\"motion\":{\"encoder_blur_px\":60.0,\"refined_blur_px\":"
         "60.01},\"decode_ms\":4.1,\"symbology_id\":\"]C0\",\"corners\":[[377.9,128.4],[627.4,"
         "128.4],[627.4,203.4],[377.9,203.4]],\"orientation_deg\":0,\"centre_belt_px\":[-3458.3,"
         "165.9],\"module_px\":2.5,\"quality\":{\"grade\":\"A\",\"grade_value\":3.9,"
         "\"indicative\":true,\"symbol_contrast\":0.83,\"r_min\":0.05,\"r_max\":0.88,"
         "\"modulation\":0.86,\"edge_contrast\":0.71,\"defects\":0.09,\"scans\":10}}";
}

/// The subscriber: each message's arrival time by its object number.
struct Arrivals {
  std::mutex mutex;
  std::vector<Clock::time_point> at;
  std::atomic<bool> subscribed{false};
  std::atomic<std::size_t> count{0};
};

void on_message(mosquitto*, void* user, const mosquitto_message* message) {
  const Clock::time_point now = Clock::now();
  auto& a = *static_cast<Arrivals*>(user);
  const std::string payload(static_cast<const char*>(message->payload),
                            static_cast<std::size_t>(message->payloadlen));
  const std::size_t object =
      std::strtoull(payload.c_str() + std::strlen("{\"object\":"), nullptr, 10);
  std::lock_guard lock(a.mutex);
  if (object < a.at.size() && a.at[object] == Clock::time_point{}) {
    a.at[object] = now;
    ++a.count;
  }
}

void on_subscribe(mosquitto*, void* user, int, int, const int*) {
  static_cast<Arrivals*>(user)->subscribed = true;
}

struct Figures {
  double p50 = 0, p99 = 0, max = 0;
  std::size_t received = 0;
};

/// `messages` results at `interval` through a publisher at `qos`, after a few
/// not counted (the connection made, the first messages through).
Figures measure(const flutterscan::session::testing::MosquittoBroker& broker, int qos,
                std::size_t messages, std::chrono::microseconds interval) {
  constexpr std::size_t kWarmup = 20;
  const std::string topic = "flutterscan-bench/qos" + std::to_string(qos);
  Arrivals arrivals;
  arrivals.at.resize(kWarmup + messages);
  mosquitto* sub = mosquitto_new(nullptr, true, &arrivals);
  mosquitto_message_callback_set(sub, on_message);
  mosquitto_subscribe_callback_set(sub, on_subscribe);
  mosquitto_int_option(sub, MOSQ_OPT_TCP_NODELAY, 1);
  if (mosquitto_connect(sub, "127.0.0.1", broker.port(), 10) != MOSQ_ERR_SUCCESS ||
      mosquitto_subscribe(sub, nullptr, topic.c_str(), qos) != MOSQ_ERR_SUCCESS ||
      mosquitto_loop_start(sub) != MOSQ_ERR_SUCCESS) {
    std::fprintf(stderr, "mqtt_bench: the subscriber could not subscribe\n");
    std::exit(1);
  }
  for (int i = 0; i < 1000 && !arrivals.subscribed; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));

  MqttConfig config;
  config.host = "127.0.0.1";
  config.port = broker.port();
  config.topic = topic;
  config.qos = qos;
  config.client_id = "flutterscan-bench-qos" + std::to_string(qos);
  MqttPublisher publisher;
  if (auto p = publisher.start(
          config, [](const std::string& s) { std::fprintf(stderr, "%s\n", s.c_str()); });
      !p.empty()) {
    std::fprintf(stderr, "mqtt_bench: %s\n", p.c_str());
    std::exit(1);
  }
  // Warm up: the connection made, a few messages through.
  for (std::size_t i = 0; i < kWarmup; ++i) {
    publisher.publish(result_line(i));
    std::this_thread::sleep_for(std::chrono::milliseconds(qos == 0 && i == 0 ? 300 : 10));
  }
  std::vector<Clock::time_point> sent(kWarmup + messages);
  Clock::time_point next = Clock::now();
  for (std::size_t i = kWarmup; i < kWarmup + messages; ++i) {
    std::this_thread::sleep_until(next);
    next += interval;
    const std::string line = result_line(i);
    sent[i] = Clock::now();
    publisher.publish(line);
  }
  for (int i = 0; i < 100 && arrivals.count < kWarmup + messages; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  publisher.stop();
  mosquitto_disconnect(sub);
  mosquitto_loop_stop(sub, false);
  mosquitto_destroy(sub);

  std::vector<double> latency_ms;
  std::lock_guard lock(arrivals.mutex);
  for (std::size_t i = kWarmup; i < kWarmup + messages; ++i)
    if (arrivals.at[i] != Clock::time_point{})
      latency_ms.push_back(
          std::chrono::duration<double, std::milli>(arrivals.at[i] - sent[i]).count());
  Figures f;
  f.received = latency_ms.size();
  f.p50 = flutterscan::session::percentile(latency_ms, 50);
  f.p99 = flutterscan::session::percentile(latency_ms, 99);
  f.max = latency_ms.empty() ? 0 : *std::max_element(latency_ms.begin(), latency_ms.end());
  return f;
}

}  // namespace

int main(int argc, char** argv) {
  std::size_t messages = 5000;
  long interval_us = 2000;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--messages")
      messages = std::strtoull(argv[i + 1], nullptr, 10);
    else if (a == "--interval-us")
      interval_us = std::strtol(argv[i + 1], nullptr, 10);
  }
  if (std::string(MOSQUITTO).empty()) {
    std::fprintf(stderr, "mqtt_bench: mosquitto is not installed (tools/install-deps)\n");
    return 1;
  }
  mosquitto_lib_init();
  const fs::path dir =
      fs::temp_directory_path() / ("flutterscan_mqtt_bench_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  flutterscan::session::testing::MosquittoBroker broker(MOSQUITTO, dir);
  if (!broker.start()) {
    std::fprintf(stderr, "mqtt_bench: mosquitto did not start (%s)\n", dir.c_str());
    return 1;
  }
  std::ifstream loadavg("/proc/loadavg");
  std::string load, one, five, fifteen;
  if (loadavg >> one >> five >> fifteen) load = one + " " + five + " " + fifteen;
  std::printf(
      "results over MQTT on loopback: %zu messages of %zu bytes, one every %ld us; "
      "publish() to the subscriber's callback (load average %s)\n\n",
      messages, result_line(0).size(), interval_us, load.c_str());
  std::printf("| QoS | received | p50 ms | p99 ms | max ms |\n|---|---|---|---|---|\n");
  for (int qos : {1, 0}) {
    const Figures f = measure(broker, qos, messages, std::chrono::microseconds(interval_us));
    std::printf("| %d | %zu of %zu | %.3f | %.3f | %.3f |\n", qos, f.received, messages, f.p50,
                f.p99, f.max);
  }
  broker.stop();
  fs::remove_all(dir);
  return 0;
}
