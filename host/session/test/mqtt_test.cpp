// Results over MQTT against a real mosquitto broker on a loopback port, read
// by mosquitto_sub with a persistent session at QoS 1: every object of a sim
// session arrives as its record in summary.json (the line TCP clients get),
// also when the broker is stopped mid-session and started again on the same
// port while objects keep coming; the retained status says "stopped" with
// the counters, and "offline" (the will) when the process dies; beyond the
// queue limit results are dropped, counted and said. And [results.mqtt] read
// from the config.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "session/mqtt_publisher.hpp"
#include "session/session.hpp"
#include "session/session_config.hpp"
#include "session/test/mosquitto_broker.hpp"
#include "session/test/session_test_support.hpp"

namespace flutterscan::session {
namespace {

namespace fs = std::filesystem;
using namespace testing;

std::vector<std::string> read_lines(const fs::path& path) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

/// mosquitto_sub on the topic: persistent session (clean session off), QoS 1,
/// each payload a line of `dir`/received.
class Subscriber {
 public:
  Subscriber(const MosquittoBroker& broker, std::string topic, fs::path dir,
             std::vector<std::string> credentials = {})
      : broker_(broker),
        topic_(std::move(topic)),
        dir_(std::move(dir)),
        credentials_(std::move(credentials)) {}
  ~Subscriber() { stop(); }

  /// \brief Makes the session on the broker (it keeps what comes for it from
  /// now on), then starts receiving; false if the broker did not acknowledge.
  bool start() {
    auto args = arguments();
    args.push_back("-E");  // exit once the broker acknowledged the subscription
    if (wait_program(spawn_program(args, dir_ / "subscribed", dir_ / "subscribe.err")) != 0)
      return false;
    pid_ = spawn_program(arguments(), dir_ / "received", dir_ / "sub.err");
    return pid_ > 0;
  }
  std::vector<std::string> received() const { return read_lines(dir_ / "received"); }
  /// \brief Waits (`seconds` at most) until `n` messages came, then a moment for any more.
  std::vector<std::string> wait_for(std::size_t n, int seconds) const {
    for (int i = 0; i < seconds * 10 && received().size() < n; ++i)
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    return received();
  }
  void stop() {
    if (pid_ <= 0) return;
    ::kill(pid_, SIGTERM);
    wait_program(pid_);
    pid_ = -1;
  }

 private:
  std::vector<std::string> arguments() const {
    std::vector<std::string> args = {MOSQUITTO_SUB,
                                     "-h",
                                     "127.0.0.1",
                                     "-p",
                                     std::to_string(broker_.port()),
                                     "-c",
                                     "-i",
                                     "flutterscan-test-sub-" + std::to_string(::getpid()),
                                     "-q",
                                     "1",
                                     "-t",
                                     topic_};
    args.insert(args.end(), credentials_.begin(), credentials_.end());
    return args;
  }
  const MosquittoBroker& broker_;
  std::string topic_;
  fs::path dir_;
  std::vector<std::string> credentials_;
  pid_t pid_ = -1;
};

MqttConfig mqtt_config(const MosquittoBroker& broker) {
  MqttConfig m;
  m.host = "127.0.0.1";
  m.port = broker.port();
  m.topic = "flutterscan-test/" + std::to_string(::getpid());
  m.client_id = "flutterscan-test-" + std::to_string(::getpid());
  return m;
}

/// The retained status message on TOPIC/status, or null.
nlohmann::json retained_status(const MosquittoBroker& broker, const std::string& topic,
                               const fs::path& dir, const std::vector<std::string>& credentials) {
  std::vector<std::string> args = {MOSQUITTO_SUB,
                                   "-h",
                                   "127.0.0.1",
                                   "-p",
                                   std::to_string(broker.port()),
                                   "-t",
                                   topic + "/status",
                                   "-C",
                                   "1",
                                   "-W",
                                   "5"};
  args.insert(args.end(), credentials.begin(), credentials.end());
  const pid_t pid = spawn_program(args, dir / "status", dir / "status.err");
  if (wait_program(pid) != 0) return nullptr;
  const auto lines = read_lines(dir / "status");
  return lines.empty() ? nullptr : nlohmann::json::parse(lines[0], nullptr, false);
}

/// Each received message equals the object's record, in order.
void expect_records(const std::vector<std::string>& received, const nlohmann::json& objects) {
  ASSERT_EQ(received.size(), objects.size());
  for (std::size_t i = 0; i < received.size(); ++i)
    EXPECT_EQ(nlohmann::json::parse(received[i], nullptr, false), objects[i]) << "object " << i;
}

TEST(MqttConfigFile, ReadsTheBrokerUrlDefaultsAndThePassword) {
  const auto tls = parse_config("[results.mqtt]\nbroker = \"mqtts://[::1]\"\n", "line3.toml");
  ASSERT_TRUE(tls.ok()) << tls.error();
  const MqttConfig& m = *tls.value().results.mqtt;
  EXPECT_EQ(m.host, "::1");
  EXPECT_EQ(m.port, 8883);
  EXPECT_TRUE(m.tls);
  EXPECT_EQ(m.topic, "flutterscan/results");
  EXPECT_EQ(m.qos, 1);
  EXPECT_EQ(m.queue_limit, 10000u);
  EXPECT_TRUE(m.client_id.starts_with("flutterscan-")) << m.client_id;
  EXPECT_TRUE(m.password.empty());

  ::setenv("FLUTTERSCAN_TEST_MQTT_PASSWORD", "s3cret", 1);
  const auto plain = parse_config(
      "[results.mqtt]\nbroker = \"mqtt://broker.line3:1884/\"\ntopic = \"plant/line3\"\n"
      "qos = 0\nclient_id = \"line3\"\nusername = \"line3\"\n"
      "password_env = \"FLUTTERSCAN_TEST_MQTT_PASSWORD\"\n",
      "line3.toml");
  ASSERT_TRUE(plain.ok()) << plain.error();
  const MqttConfig& p = *plain.value().results.mqtt;
  EXPECT_EQ(p.host, "broker.line3");
  EXPECT_EQ(p.port, 1884);
  EXPECT_FALSE(p.tls);
  EXPECT_EQ(p.topic, "plant/line3");
  EXPECT_EQ(p.qos, 0);
  EXPECT_EQ(p.client_id, "line3");
  EXPECT_EQ(p.password, "s3cret");
  ::unsetenv("FLUTTERSCAN_TEST_MQTT_PASSWORD");

  EXPECT_FALSE(parse_config("", "line3.toml").value().results.mqtt.has_value());
}

#define REQUIRE_MOSQUITTO()                                                     \
  if (std::string(MOSQUITTO).empty() || std::string(MOSQUITTO_SUB).empty() ||   \
      std::string(MOSQUITTO_PASSWD).empty())                                    \
  GTEST_SKIP() << "mosquitto, mosquitto_sub or mosquitto_passwd not installed " \
                  "(tools/install-deps)"

// The broker takes only a user with the password; the session reads it from
// its password_file ([results.mqtt] read as a config file is).
TEST(MqttResults, EveryObjectArrivesAsItsRecord) {
  REQUIRE_MOSQUITTO();
  const ScratchFolder scratch("mqtt");
  const fs::path& dir = scratch.path();
  fs::create_directories(dir / "broker");
  ASSERT_EQ(wait_program(spawn_program({MOSQUITTO_PASSWD, "-b", "-c",
                                        (dir / "broker" / "passwords").string(), "line3", "s3cret"},
                                       dir / "passwd.out", dir / "passwd.err")),
            0);
  BrokerOptions options;
  options.password_file = dir / "broker" / "passwords";
  MosquittoBroker broker(MOSQUITTO, dir / "broker", options);
  ASSERT_TRUE(broker.start()) << "mosquitto did not start: see " << dir;
  std::ofstream(dir / "password") << "s3cret\n";
  fs::permissions(dir / "password", fs::perms::owner_read | fs::perms::owner_write);
  const auto file = parse_config("[results.mqtt]\nbroker = \"" + broker.url() +
                                     "\"\nusername = \"line3\"\npassword_file = \"" +
                                     (dir / "password").string() + "\"\n",
                                 "line3.toml");
  ASSERT_TRUE(file.ok()) << file.error();
  SessionConfig config = small_sim_config(dir / "session", 90);
  config.output.report = false;
  config.results.mqtt = file.value().results.mqtt;
  config.results.mqtt->topic = mqtt_config(broker).topic;
  Subscriber subscriber(broker, config.results.mqtt->topic, dir, {"-u", "line3", "-P", "s3cret"});
  ASSERT_TRUE(subscriber.start());

  std::atomic<bool> stop{false};
  const SessionOutcome outcome = run_session(config, stop, {});
  ASSERT_EQ(outcome.error, "");
  const auto& objects = outcome.summary["object_results"];
  ASSERT_GE(objects.size(), 2u);
  expect_records(subscriber.wait_for(objects.size(), 30), objects);
  const auto& counters = outcome.summary["results"]["mqtt"];
  EXPECT_EQ(counters["published"], objects.size());
  EXPECT_EQ(counters["dropped"], 0);
  EXPECT_EQ(counters["undelivered"], 0);
  EXPECT_EQ(counters["reconnects"], 0);
  EXPECT_EQ(counters["broker"], broker.url());

  const auto status =
      retained_status(broker, config.results.mqtt->topic, dir, {"-u", "line3", "-P", "s3cret"});
  ASSERT_TRUE(status.is_object()) << status;
  EXPECT_EQ(status["state"], "stopped");
  EXPECT_EQ(status["published"], objects.size());
  EXPECT_EQ(status["waiting"], 0);
}

// A process that dies without a goodbye: the broker publishes the will, and the
// retained status says "offline" (it said "running" while the process lived).
TEST(MqttResults, TheBrokerMarksADeadSessionOffline) {
  REQUIRE_MOSQUITTO();
  const ScratchFolder scratch("mqtt_will");
  const fs::path& dir = scratch.path();
  fs::create_directories(dir / "broker");
  MosquittoBroker broker(MOSQUITTO, dir / "broker");
  ASSERT_TRUE(broker.start()) << "mosquitto did not start: see " << dir;
  const MqttConfig config = mqtt_config(broker);
  const pid_t child = ::fork();
  if (child == 0) {  // publishes a result, then dies
    MqttPublisher publisher;
    if (!publisher.start(config, {}).empty()) _exit(1);
    publisher.publish(R"({"object":1,"status":"NO-READ"})");
    // Until the result is acknowledged and the test has read "running".
    for (int i = 0; i < 600 && (publisher.counters().published == 0 || !fs::exists(dir / "die"));
         ++i)
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    _exit(publisher.counters().published == 1 ? 0 : 2);
  }
  const auto running = retained_status(broker, config.topic, dir, {});
  std::ofstream(dir / "die") << "now\n";
  EXPECT_EQ(wait_program(child), 0);
  ASSERT_TRUE(running.is_object()) << running;
  EXPECT_EQ(running["state"], "running");
  EXPECT_EQ(running["client_id"], config.client_id);
  nlohmann::json status;
  for (int i = 0; i < 50 && (!status.is_object() || status["state"] != "offline"); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    status = retained_status(broker, config.topic, dir, {});
  }
  ASSERT_TRUE(status.is_object()) << status;
  EXPECT_EQ(status["state"], "offline");
  EXPECT_EQ(status["client_id"], config.client_id);
}

// The broker away from the start and queue_limit = 2: two results wait, the
// next three are dropped, counted and said once; the two arrive when the broker
// comes, and the next result is taken again, said with the count of the dropped.
TEST(MqttResults, BeyondTheQueueLimitResultsAreDroppedCountedAndSaid) {
  REQUIRE_MOSQUITTO();
  const ScratchFolder scratch("mqtt_overflow");
  const fs::path& dir = scratch.path();
  fs::create_directories(dir / "broker");
  MosquittoBroker broker(MOSQUITTO, dir / "broker");
  MqttConfig config = mqtt_config(broker);
  config.queue_limit = 2;
  // The subscriber's session made while the broker is up, kept in its persistence.
  ASSERT_TRUE(broker.start()) << "mosquitto did not start: see " << dir;
  Subscriber subscriber(broker, config.topic, dir);
  ASSERT_TRUE(subscriber.start());
  subscriber.stop();
  broker.stop();

  std::mutex said_mutex;
  std::vector<std::string> said;
  MqttPublisher publisher;
  ASSERT_EQ(publisher.start(config,
                            [&](const std::string& text) {
                              std::lock_guard lock(said_mutex);
                              said.push_back(text);
                            }),
            "");
  std::vector<std::string> lines;
  for (int i = 1; i <= 6; ++i)
    lines.push_back(R"({"object":)" + std::to_string(i) + R"(,"status":"NO-READ"})");
  for (int i = 0; i < 5; ++i) publisher.publish(lines[i]);
  EXPECT_EQ(publisher.counters().dropped, 3u);
  EXPECT_EQ(publisher.counters().queued_max, 2u);

  ASSERT_TRUE(broker.start());
  ASSERT_TRUE(subscriber.start());
  for (int i = 0; i < 600 && publisher.counters().published < 2; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  publisher.publish(lines[5]);
  publisher.stop(std::chrono::seconds(20));
  const MqttCounters c = publisher.counters();
  EXPECT_EQ(c.published, 3u);
  EXPECT_EQ(c.dropped, 3u);
  EXPECT_EQ(c.undelivered, 0u);
  EXPECT_EQ(subscriber.wait_for(3, 30), (std::vector<std::string>{lines[0], lines[1], lines[5]}));

  std::lock_guard lock(said_mutex);
  const auto count = [&](const std::string& text) {
    return std::count_if(said.begin(), said.end(),
                         [&](const std::string& s) { return s.find(text) != std::string::npos; });
  };
  EXPECT_EQ(count("results are dropped until it takes them"), 1) << ::testing::PrintToString(said);
  EXPECT_EQ(count("takes results again; 3 dropped meanwhile"), 1) << ::testing::PrintToString(said);
}

/// Runs openssl with `args` in `dir`; true if it succeeded.
bool openssl(const std::vector<std::string>& args, const fs::path& dir) {
  std::vector<std::string> all = {OPENSSL};
  all.insert(all.end(), args.begin(), args.end());
  return wait_program(spawn_program(all, dir / "openssl.out", dir / "openssl.err")) == 0;
}

/// A CA ("NAME.crt", "NAME.key") made in `dir`.
bool make_ca(const fs::path& dir, const std::string& name) {
  return openssl({"req", "-x509", "-newkey", "rsa:2048", "-nodes", "-days", "1", "-subj",
                  "/CN=flutterscan test " + name, "-keyout", (dir / (name + ".key")).string(),
                  "-out", (dir / (name + ".crt")).string()},
                 dir);
}

// TLS (mqtts://): the broker's certificate, for 127.0.0.1, signed by a CA the
// config's ca_file names: every result arrives. With another CA's file the
// client refuses the broker: nothing is published, the result is counted as
// undelivered.
TEST(MqttResults, OverTlsOnlyToABrokerTheCaVouchesFor) {
  REQUIRE_MOSQUITTO();
  if (std::string(OPENSSL).empty()) GTEST_SKIP() << "openssl not installed (tools/install-deps)";
  const ScratchFolder scratch("mqtt_tls");
  const fs::path& dir = scratch.path();
  fs::create_directories(dir / "broker");
  std::ofstream(dir / "san.cnf") << "subjectAltName = IP:127.0.0.1\n";
  ASSERT_TRUE(make_ca(dir, "ca") && make_ca(dir, "other-ca"));
  ASSERT_TRUE(openssl({"req", "-newkey", "rsa:2048", "-nodes", "-subj", "/CN=127.0.0.1", "-keyout",
                       (dir / "broker.key").string(), "-out", (dir / "broker.csr").string()},
                      dir));
  ASSERT_TRUE(
      openssl({"x509", "-req", "-days", "1", "-in", (dir / "broker.csr").string(), "-CA",
               (dir / "ca.crt").string(), "-CAkey", (dir / "ca.key").string(), "-CAcreateserial",
               "-extfile", (dir / "san.cnf").string(), "-out", (dir / "broker.crt").string()},
              dir));
  BrokerOptions options;
  options.certificate = dir / "broker.crt";
  options.key = dir / "broker.key";
  MosquittoBroker broker(MOSQUITTO, dir / "broker", options);
  ASSERT_TRUE(broker.start()) << "mosquitto did not start: see " << dir;
  const std::string topic = mqtt_config(broker).topic;
  Subscriber subscriber(broker, topic, dir, {"--cafile", (dir / "ca.crt").string()});
  ASSERT_TRUE(subscriber.start());

  const auto config_with = [&](const std::string& ca) {
    auto c = parse_config(
        "[results.mqtt]\nbroker = \"mqtts://127.0.0.1:" + std::to_string(broker.port()) +
            "\"\ntopic = \"" + topic + "\"\nca_file = \"" + (dir / ca).string() + "\"\n",
        "line3.toml");
    EXPECT_TRUE(c.ok()) << c.error();
    return *c.value().results.mqtt;
  };
  const std::vector<std::string> lines = {R"({"object":1,"status":"READ","value":"FS-1"})",
                                          R"({"object":2,"status":"NO-READ"})"};
  {
    MqttPublisher publisher;
    ASSERT_EQ(publisher.start(config_with("ca.crt"), {}), "");
    for (const auto& line : lines) publisher.publish(line);
    publisher.stop(std::chrono::seconds(20));
    EXPECT_EQ(publisher.counters().published, lines.size());
    EXPECT_EQ(publisher.counters().undelivered, 0u);
  }
  EXPECT_EQ(subscriber.wait_for(lines.size(), 30), lines);

  MqttPublisher refused;
  std::mutex said_mutex;
  std::vector<std::string> said;
  ASSERT_EQ(refused.start(config_with("other-ca.crt"),
                          [&](const std::string& text) {
                            std::lock_guard lock(said_mutex);
                            said.push_back(text);
                          }),
            "");
  refused.publish(lines[0]);
  refused.stop(std::chrono::seconds(3));
  EXPECT_EQ(refused.counters().published, 0u);
  EXPECT_EQ(refused.counters().undelivered, 1u);
  EXPECT_EQ(subscriber.received(), lines);
  // Said, not silent: the result waiting, the handshake's failure, the result not delivered.
  std::lock_guard lock(said_mutex);
  const std::string all = ::testing::PrintToString(said);
  EXPECT_NE(all.find("results wait for it"), std::string::npos) << all;
  EXPECT_NE(all.find("certificate verify failed"), std::string::npos) << all;
  EXPECT_NE(all.find("1 results were not acknowledged"), std::string::npos) << all;
}

// The broker stops (SIGTERM: it saves the subscriber's session) once objects
// have arrived, and starts again on the same port once the session has
// finished two more objects while it was away; the session goes on until two
// more arrive after that. Every object arrives; one the broker took but had
// not acknowledged when it stopped may arrive twice (QoS 1: at least once).
TEST(MqttResults, NothingIsLostAcrossABrokerRestart) {
  REQUIRE_MOSQUITTO();
  const ScratchFolder scratch("mqtt_restart");
  fs::create_directories(scratch.path() / "broker");
  MosquittoBroker broker(MOSQUITTO, scratch.path() / "broker");
  ASSERT_TRUE(broker.start()) << "mosquitto did not start: see " << scratch.path();
  SessionConfig config = small_sim_config(scratch.path() / "session", 20000);
  config.output.report = false;
  config.results.mqtt = mqtt_config(broker);
  Subscriber subscriber(broker, config.results.mqtt->topic, scratch.path());
  ASSERT_TRUE(subscriber.start());

  std::atomic<bool> stop{false}, ended{false};
  std::atomic<std::uint64_t> objects_finished{0}, progress_lines{0};
  std::mutex messages_mutex;
  std::vector<std::string> messages;
  SessionHooks hooks;
  hooks.progress = [&](const Progress& p) {
    objects_finished = p.objects;
    ++progress_lines;
  };
  hooks.message = [&](const std::string& text) {
    std::lock_guard lock(messages_mutex);
    messages.push_back(text);
  };
  SessionOutcome outcome;
  std::thread session([&] {
    outcome = run_session(config, stop, hooks);
    ended = true;
  });
  const auto wait_until = [&](const auto& done, int seconds) {
    for (int i = 0; i < seconds * 10 && !done() && !ended; ++i)
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    return done();
  };

  const bool arrived = wait_until([&] { return subscriber.received().size() >= 2; }, 300);
  broker.stop();
  const std::size_t received_at_stop = subscriber.received().size();
  // At least the objects finished by the stop: the count of the second progress
  // line after it (the first may have been counted just before).
  const std::uint64_t lines_at_stop = progress_lines;
  wait_until([&] { return progress_lines > lines_at_stop + 1; }, 60);
  const std::uint64_t finished_at_stop = objects_finished;
  const bool finished_while_away =
      wait_until([&] { return objects_finished >= finished_at_stop + 2; }, 300);
  const bool restarted = broker.start();
  const std::size_t received_at_restart = subscriber.received().size();
  const bool arrived_after =
      wait_until([&] { return subscriber.received().size() >= received_at_restart + 2; }, 300);
  const bool ran_throughout = !ended;
  stop = true;
  session.join();

  ASSERT_TRUE(arrived && finished_while_away && restarted && arrived_after && ran_throughout)
      << arrived << finished_while_away << restarted << arrived_after << ran_throughout
      << " error: " << outcome.error;
  ASSERT_EQ(outcome.error, "");
  const auto& objects = outcome.summary["object_results"];
  std::vector<std::string> received = subscriber.wait_for(objects.size(), 60);
  // A message sent again after the restart is the same line: drop repeats.
  std::vector<std::string> distinct;
  for (const auto& line : received)
    if (std::find(distinct.begin(), distinct.end(), line) == distinct.end())
      distinct.push_back(line);
  expect_records(distinct, objects);
  const auto& counters = outcome.summary["results"]["mqtt"];
  EXPECT_EQ(counters["published"], objects.size());
  EXPECT_EQ(counters["dropped"], 0);
  EXPECT_EQ(counters["undelivered"], 0);
  EXPECT_GE(counters["reconnects"], 1);
  // The publisher said so: the broker lost, then back with the results finished
  // meanwhile (two at least) waiting.
  std::lock_guard lock(messages_mutex);
  bool lost = false;
  long waiting_at_reconnect = -1;
  for (const auto& m : messages) {
    lost = lost || m.find("lost: reconnecting") != std::string::npos;
    if (const auto again = m.find("again; "); again != std::string::npos)
      waiting_at_reconnect = std::strtol(m.c_str() + again + 7, nullptr, 10);
  }
  std::printf(
      "%zu objects, %zu received before the broker stopped, %ld waiting at the "
      "reconnect, %zu messages in all\n",
      objects.size(), received_at_stop, waiting_at_reconnect, received.size());
  EXPECT_TRUE(lost) << ::testing::PrintToString(messages);
  EXPECT_GE(waiting_at_reconnect, 2) << ::testing::PrintToString(messages);
}

}  // namespace
}  // namespace flutterscan::session
