#include "session/session_config.hpp"

#include <toml++/toml.h>

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <limits>
#include <sstream>
#include <type_traits>
#include <utility>

#include "codes/library.hpp"
#include "flutterscan/common/protocol.hpp"
#include "imaging/capture_descriptor.hpp"
#include "imaging/limits.hpp"

namespace flutterscan::session {
namespace {

using ConfigResult = Result<SessionConfig, std::string>;

class TableReader;

/// \brief One key a table may hold and how it is read: by TableReader::get's type rules
/// into a value; by a reader of its own, whose problem (not empty) ends the parse; or,
/// with neither, by the caller after TableReader::read().
struct Field {
  template <typename T>
  requires(!std::is_invocable_v<T&, TableReader&>) Field(const char* k, T& value);
  Field(const char* k, std::function<std::string(TableReader&)> own)
      : key(k), read(std::move(own)) {}
  explicit Field(const char* k) : key(k) {}

  const char* key;
  std::function<std::string(TableReader&)> read;
};

/// Reads typed values out of one table, remembering the first problem.
class TableReader {
 public:
  TableReader(const toml::table* table, std::string prefix, std::string origin, std::string& error)
      : table_(table), prefix_(std::move(prefix)), origin_(std::move(origin)), error_(error) {}
  /// [`name`] of `parent` (none: nothing is read), "NAME." in messages.
  TableReader(const toml::table& parent, const std::string& name, std::string origin,
              std::string& error)
      : TableReader(parent[name].as_table(), name + ".", std::move(origin), error) {}

  /// Every field in turn, once no key of the table is unknown to `fields`: the problem
  /// that ends the parse (an unknown key, or one a field's own reader found), else "". A
  /// value of the wrong type does not end it: the first such problem waits in `error`.
  std::string read(std::initializer_list<Field> fields) {
    if (table_ == nullptr) return {};
    for (const auto& [key, node] : *table_)
      if (std::none_of(fields.begin(), fields.end(),
                       [&](const Field& f) { return key.str() == f.key; })) {
        std::ostringstream where;
        where << origin_ << ":" << node.source().begin.line << ": unknown key " << prefix_
              << key.str();
        return where.str();
      }
    for (const Field& f : fields)
      if (f.read)
        if (auto problem = f.read(*this); !problem.empty()) return problem;
    return {};
  }

  template <typename T>
  void get(const char* key, T& value) {
    if (table_ == nullptr || !error_.empty()) return;
    const toml::node* node = table_->get(key);
    if (node == nullptr) return;
    if constexpr (std::is_same_v<T, bool>) {
      if (auto v = node->value_exact<bool>()) return void(value = *v);
      fail(key, "true or false");
    } else if constexpr (std::is_same_v<T, std::string>) {
      if (auto v = node->value_exact<std::string>()) return void(value = *v);
      fail(key, "a string");
    } else if constexpr (std::is_floating_point_v<T>) {
      if (auto v = node->value<double>(); v && std::isfinite(*v)) return void(value = *v);
      fail(key, "a number");
    } else {
      if (auto v = node->value_exact<std::int64_t>()) {
        if (*v < 0 && std::is_unsigned_v<T>) return fail(key, "an integer >= 0");
        // A value the field cannot hold is refused, never truncated into range.
        if (!std::in_range<T>(*v))
          return fail(key, "an integer within " + std::to_string(std::numeric_limits<T>::min()) +
                               ".." + std::to_string(std::numeric_limits<T>::max()) + " (got " +
                               std::to_string(*v) + ")");
        return void(value = static_cast<T>(*v));
      }
      fail(key, "an integer");
    }
  }

  template <typename T>
  void get(const char* key, std::optional<T>& value) {
    if (table_ == nullptr || table_->get(key) == nullptr) return;
    T v{};
    get(key, v);
    if (error_.empty()) value = v;
  }

  /// A field whose string names a value: `set` takes the name (false: it names none) and
  /// "ORIGIN: KEY " + `what` of the name is the problem where it names none. A value of
  /// another type waits in `error`, as get's do.
  static Field name(const char* key, std::function<bool(const std::string&)> set,
                    std::function<std::string(const std::string&)> what) {
    return Field(key, [key, set = std::move(set), what = std::move(what)](TableReader& r) {
      std::string given;
      r.get(key, given);
      if (given.empty() || set(given)) return std::string();
      return r.without_line(key, " " + what(given));
    });
  }

  /// The table's node at `key` (nullptr: none, or no table).
  const toml::node* node(const char* key) const {
    return table_ == nullptr ? nullptr : table_->get(key);
  }

  /// "ORIGIN:LINE: KEY" and `rest`, the line of `key` (of the table where it has none).
  std::string at(const char* key, const std::string& rest) const {
    const toml::node* n = node(key);
    std::ostringstream where;
    where << origin_ << ":" << (n ? n->source().begin.line : table_->source().begin.line) << ": "
          << prefix_ << key << rest;
    return where.str();
  }

  /// "ORIGIN: KEY" and `rest`: the problems that name no line.
  std::string without_line(const char* key, const std::string& rest) const {
    return origin_ + ": " + prefix_ + key + rest;
  }

 private:
  void fail(const char* key, const std::string& wanted) {
    if (error_.empty()) error_ = at(key, " must be " + wanted);
  }

  const toml::table* table_;
  std::string prefix_;
  std::string origin_;
  std::string& error_;
};

template <typename T>
requires(!std::is_invocable_v<T&, TableReader&>) Field::Field(const char* k, T& value)
    : key(k), read([k, &value](TableReader& r) {
        r.get(k, value);
        return std::string();
      }) {}

/// A number as the config would show it (shortest form that reads back).
std::string number_text(double value) {
  std::ostringstream text;
  text.precision(15);
  text << value;
  return text.str();
}

/// " (got VALUE)".
std::string got_text(double value) {
  return " (got " + number_text(value) + ")";
}

/// "KEY = VALUE is outside RANGE": the key, what it was and what it may be.
std::string outside(const std::string& key, double value, const std::string& range,
                    const std::string& why = {}) {
  return key + " = " + number_text(value) + " is outside " + range + (why.empty() ? "" : ": ") +
         why;
}

/// The broker URL "mqtt://HOST[:PORT]" or "mqtts://HOST[:PORT]" (HOST may be "[v6]") into
/// `m`; false if it is not one.
bool parse_broker_url(const std::string& url, MqttConfig& m) {
  std::string rest;
  if (url.starts_with("mqtt://")) {
    m.tls = false;
    m.port = 1883;
    rest = url.substr(7);
  } else if (url.starts_with("mqtts://")) {
    m.tls = true;
    m.port = 8883;
    rest = url.substr(8);
  } else {
    return false;
  }
  if (!rest.empty() && rest.back() == '/') rest.pop_back();
  // HOST, or [IPv6 address], then :PORT or nothing.
  std::size_t host_end = rest.starts_with("[") ? rest.find(']') : rest.find(':');
  if (rest.starts_with("[")) {
    if (host_end == std::string::npos) return false;
    m.host = rest.substr(1, host_end - 1);
    ++host_end;
  } else {
    m.host = rest.substr(0, host_end);
  }
  const auto is_bad = [](char ch) {
    return std::isspace(static_cast<unsigned char>(ch)) || ch == '/' || ch == '@' || ch == '?';
  };
  if (m.host.empty() || std::any_of(m.host.begin(), m.host.end(), is_bad)) return false;
  if (host_end >= rest.size()) return true;
  const std::string port = rest.substr(host_end + 1);
  const auto digit = [](char ch) { return std::isdigit(static_cast<unsigned char>(ch)) != 0; };
  if (rest[host_end] != ':' || port.empty() || port.size() > 5 ||
      !std::all_of(port.begin(), port.end(), digit))
    return false;
  m.port = std::stoi(port);
  return m.port >= 1 && m.port <= 65535;
}

/// The first line of a password file that only its owner and group may read; error if not.
std::string read_password_file(const std::string& path, std::string& password) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode))
    return "'" + path + "' is not a readable file";
  if ((st.st_mode & S_IROTH) != 0) {
    char mode[8];
    std::snprintf(mode, sizeof mode, "%04o", static_cast<unsigned>(st.st_mode & 07777));
    return "'" + path + "' is readable by every user (mode " + mode +
           "): a password file must not be (chmod o-r)";
  }
  std::ifstream in(path);
  if (!in) return "'" + path + "' is not a readable file";
  std::getline(in, password);
  if (!password.empty() && password.back() == '\r') password.pop_back();
  if (password.empty()) return "'" + path + "' has no password on its first line";
  return {};
}

/// [results.mqtt]: every key checked where it is (the error names the file, line and key).
std::string parse_mqtt(const toml::table& t, const std::string& origin, MqttConfig& m) {
  std::string error, broker, password_file, password_env;
  TableReader r(&t, "results.mqtt.", origin, error);
  if (auto p = r.read({{"broker", broker},
                       {"topic", m.topic},
                       {"qos", m.qos},
                       {"client_id", m.client_id},
                       {"queue_limit", m.queue_limit},
                       {"username", m.username},
                       {"password_file", password_file},
                       {"password_env", password_env},
                       {"ca_file", m.ca_file},
                       {"cert_file", m.cert_file},
                       {"key_file", m.key_file}});
      !p.empty())
    return p;
  if (!error.empty()) return error;
  const auto problem = [&](const char* key, const std::string& what) {
    return r.at(key, " " + what);
  };
  if (broker.empty())
    return problem("broker", "must be given: \"mqtt://HOST[:PORT]\" or \"mqtts://HOST[:PORT]\"");
  if (!parse_broker_url(broker, m))
    return problem("broker", "'" + broker +
                                 "' is not mqtt://HOST[:PORT] or mqtts://HOST[:PORT] (port "
                                 "1..65535)");
  if (m.topic.empty() || m.topic.size() > 1024 ||
      m.topic.find_first_of(std::string("+#\0", 3)) != std::string::npos)
    return problem("topic", "must be 1..1024 bytes without the wildcards + and #");
  if (m.qos < 0 || m.qos > 2) return problem("qos", "must be 0, 1 or 2" + got_text(m.qos));
  if (t.get("client_id") != nullptr && (m.client_id.empty() || m.client_id.size() > 256 ||
                                        !std::all_of(m.client_id.begin(), m.client_id.end(),
                                                     [](char ch) { return ch > ' ' && ch < 127; })))
    return problem("client_id", "must be 1..256 printable ASCII characters without spaces");
  if (m.queue_limit < 1 || m.queue_limit > kMaxMqttQueue)
    return problem("queue_limit", "must be within 1.." + std::to_string(kMaxMqttQueue) +
                                      " results (each holds its line)" +
                                      got_text(static_cast<double>(m.queue_limit)));
  if (!password_file.empty() && !password_env.empty())
    return problem("password_env", "and results.mqtt.password_file: give one of them");
  if (!password_file.empty()) {
    if (auto why = read_password_file(password_file, m.password); !why.empty())
      return problem("password_file", why);
  } else if (t.get("password_file") != nullptr) {
    return problem("password_file", "must not be empty");
  }
  if (!password_env.empty()) {
    const char* value = std::getenv(password_env.c_str());
    if (value == nullptr || *value == '\0')
      return problem("password_env", "names " + password_env + ", which is not set");
    m.password = value;
  } else if (t.get("password_env") != nullptr) {
    return problem("password_env", "must not be empty");
  }
  if (!m.password.empty() && m.username.empty())
    return problem("username", "must be given with a password");
  for (const auto& [key, path] :
       {std::pair{"ca_file", &m.ca_file}, std::pair{"cert_file", &m.cert_file},
        std::pair{"key_file", &m.key_file}}) {
    if (t.get(key) == nullptr) continue;
    if (!m.tls) return problem(key, "needs an mqtts:// broker");
    std::ifstream file(*path);
    if (path->empty() || !file) return problem(key, "'" + *path + "' is not a readable file");
  }
  if (m.cert_file.empty() != m.key_file.empty())
    return problem(m.cert_file.empty() ? "cert_file" : "key_file",
                   "must be given with results.mqtt." +
                       std::string(m.cert_file.empty() ? "key_file" : "cert_file"));
  if (m.client_id.empty()) {
    char host[256] = "host";
    ::gethostname(host, sizeof host - 1);
    m.client_id = "flutterscan-" + std::string(host);
  }
  return {};
}

}  // namespace

Result<SessionConfig, std::string> parse_config(const std::string& text,
                                                const std::string& origin) {
  toml::table root;
  try {
    root = toml::parse(text, origin);
  } catch (const toml::parse_error& e) {
    std::ostringstream where;
    where << origin << ":" << e.source().begin.line << ": " << e.description();
    return ConfigResult::failure(where.str());
  }
  SessionConfig c;
  std::string error;
  if (auto p = TableReader(&root, "", origin, error)
                   .read({Field("camera"), Field("controller"), Field("optics"),
                          Field("processing"), Field("output"), Field("results")});
      !p.empty())
    return ConfigResult::failure(p);
  TableReader camera(root, "camera", origin, error);
  std::string pixel_format, trigger;
  if (auto p = camera.read({{"spec", c.camera.spec},
                            {"width", c.camera.settings.width},
                            {"height", c.camera.settings.height},
                            {"exposure_us", c.camera.settings.exposure_us},
                            {"gain_db", c.camera.settings.gain_db},
                            {"frame_rate_hz", c.camera.settings.frame_rate_hz},
                            {"pixel_format", pixel_format},
                            {"trigger", trigger},
                            Field("options")});
      !p.empty())
    return ConfigResult::failure(p);
  if (!error.empty()) return ConfigResult::failure(error);
  if (!pixel_format.empty()) {
    c.camera.settings.pixel_format = capture::pixel_format_from_name(pixel_format);
    if (!c.camera.settings.pixel_format)
      return ConfigResult::failure(
          camera.without_line("pixel_format", " '" + pixel_format + "' is not a known format"));
  }
  if (!trigger.empty()) {
    auto mode = capture::trigger_mode_from_name(trigger);
    if (!mode)
      return ConfigResult::failure(
          camera.without_line("trigger", " must be free-run, software or line0"));
    c.camera.settings.trigger = *mode;
  }
  if (const toml::node* options = camera.node("options"); options && options->is_table()) {
    for (const auto& [key, node] : *options->as_table()) {
      std::string value;
      if (auto s = node.value_exact<std::string>())
        value = *s;
      else if (auto i = node.value_exact<std::int64_t>())
        value = std::to_string(*i);
      else if (auto d = node.value_exact<double>()) {
        std::ostringstream number;
        number.precision(17);
        number << *d;
        value = number.str();
      } else if (auto b = node.value_exact<bool>())
        value = *b ? "true" : "false";
      else
        return ConfigResult::failure(camera.without_line(
            "options", "." + std::string(key.str()) + " must be a string, number or boolean"));
      c.camera.options.emplace_back(std::string(key.str()), value);
    }
  }
  TableReader controller(root, "controller", origin, error);
  if (auto p = controller.read({{"spec", c.controller.spec},
                                {"code", c.controller.code},
                                {"slot_time_us", c.controller.slot_time_us},
                                {"sync", c.controller.sync},
                                {"frame_period_us", c.controller.frame_period_us},
                                {"probe_frames", c.controller.probe_frames}});
      !p.empty())
    return ConfigResult::failure(p);
  TableReader optics(root, "optics", origin, error);
  // Three rows (camera channels) of three numbers >= 0.
  auto crosstalk = [&](TableReader& r) -> std::string {
    const toml::node* node = r.node("crosstalk");
    if (node == nullptr) return {};
    const toml::array* rows = node->as_array();
    std::vector<double> values;
    bool ok = rows != nullptr && rows->size() == 3;
    for (std::size_t i = 0; ok && i < 3; ++i) {
      const toml::array* row = rows->get(i)->as_array();
      ok = row != nullptr && row->size() == 3;
      for (std::size_t j = 0; ok && j < 3; ++j) {
        auto v = row->get(j)->value<double>();
        ok = v.has_value() && *v >= 0;
        if (ok) values.push_back(*v);
      }
    }
    if (!ok) return r.at("crosstalk", " must be 3 rows of 3 numbers >= 0 (rows = camera channels)");
    c.optics.crosstalk = values;
    return {};
  };
  if (auto p = optics.read({{"px_per_count", c.optics.px_per_count},
                            {"direction", c.optics.direction},
                            {"electrons", c.optics.electrons},
                            {"paper_reflectance", c.optics.paper_reflectance},
                            {"cap", c.optics.cap},
                            {"read_noise_e", c.optics.read_noise_e},
                            {"full_well_e", c.optics.full_well_e},
                            {"black_level_dn", c.optics.black_level_dn},
                            {"gain_e_per_dn", c.optics.gain_e_per_dn},
                            {"bit_depth", c.optics.bit_depth},
                            {"encoder", c.optics.encoder},
                            {"nominal_blur_px", c.optics.nominal_blur_px},
                            {"line_time_us", c.optics.line_time_us},
                            {"flat_field", c.optics.flat_field},
                            {"crosstalk", crosstalk}});
      !p.empty())
    return ConfigResult::failure(p);
  c.optics.electrons_given = optics.node("electrons") != nullptr;
  TableReader processing(root, "processing", origin, error);
  // "auto" (-1) or a number of ms.
  auto auto_or_ms = [](const char* key, double& ms) {
    return Field(key, [key, &ms](TableReader& r) -> std::string {
      if (const toml::node* budget = r.node(key); budget && budget->is_string()) {
        if (budget->value_exact<std::string>() != "auto")
          return r.at(key, " must be \"auto\" or a number of ms");
        ms = -1;
      } else {
        r.get(key, ms);
      }
      return {};
    });
  };
  // A list of second-pass tries, its problem on its line.
  auto tries = [&](TableReader& r) -> std::string {
    std::string names;
    r.get("second_pass_tries", names);
    if (!error.empty() || r.node("second_pass_tries") == nullptr) return {};
    std::string problem;
    const auto parsed = parse_second_pass_tries(names, problem);
    if (!parsed) return r.at("second_pass_tries", ": " + problem);
    c.processing.second_pass_tries = *parsed;
    return {};
  };
  if (auto p = processing.read(
          {TableReader::name(
               "method",
               [&](const std::string& n) { return set_processing_method(n, c.processing); },
               [](const std::string& n) { return "'" + n + "' is none of " + kProcessingMethods; }),
           auto_or_ms("second_pass_ms", c.processing.second_pass_ms),
           auto_or_ms("decode_ms", c.processing.decode_ms),
           auto_or_ms("latency_ms", c.processing.latency_ms),
           {"workers", c.processing.workers},
           {"threads_per_worker", c.processing.threads_per_worker},
           {"queue_depth", c.processing.queue_depth},
           {"max_frames", c.processing.max_frames},
           {"max_seconds", c.processing.max_seconds},
           {"match_tolerance_us", c.processing.match_tolerance_us},
           {"object_match_px", c.processing.object_match_px},
           {"choose_model", c.processing.choose_model},
           {"blur_check_every", c.processing.blur_check_every},
           {"blur_tolerance", c.processing.blur_tolerance_pct},
           {"refine_when_behind", c.processing.refine_when_behind},
           {"symbologies", c.processing.symbologies},
           {"try_rotate", c.processing.try_rotate},
           {"second_pass_tries", tries},
           TableReader::name(
               "decode_area",
               [&](const std::string& n) {
                 const auto area = reader::decode_area_from_name(n);
                 if (area) c.processing.decode_area = *area;
                 return area.has_value();
               },
               [](const std::string& n) { return "'" + n + "' is neither labels nor frame"; })});
      !p.empty())
    return ConfigResult::failure(p);
  TableReader output(root, "output", origin, error);
  if (auto p = output.read({{"dir", c.output.dir},
                            {"timestamped_subfolder", c.output.timestamped_subfolder},
                            {"keep_first_frames", c.output.keep_first_frames},
                            {"keep_failed_frames", c.output.keep_failed_frames},
                            {"disk_budget_mb", c.output.disk_budget_mb},
                            {"report", c.output.report}});
      !p.empty())
    return ConfigResult::failure(p);
  TableReader results(root, "results", origin, error);
  auto mqtt = [&](TableReader& r) -> std::string {
    const toml::node* node = r.node("mqtt");
    if (node == nullptr) return {};
    if (!node->is_table()) return r.at("mqtt", " must be a table ([results.mqtt])");
    MqttConfig m;
    if (auto p = parse_mqtt(*node->as_table(), origin, m); !p.empty()) return p;
    c.results.mqtt = std::move(m);
    return {};
  };
  if (auto p = results.read({{"tcp_port", c.results.tcp_port},
                             {"tcp_bind", c.results.tcp_bind},
                             {"serial", c.results.serial},
                             {"serial_baud", c.results.serial_baud},
                             {"mqtt", mqtt}});
      !p.empty())
    return ConfigResult::failure(p);
  if (!error.empty()) return ConfigResult::failure(error);
  return ConfigResult::success(std::move(c));
}

Result<SessionConfig, std::string> load_config(const std::string& path) {
  toml::table root;
  std::ifstream in(path);
  if (!in) return ConfigResult::failure("cannot read config '" + path + "'");
  std::ostringstream text;
  text << in.rdbuf();
  return parse_config(text.str(), path);
}

std::string check_config(SessionConfig& c) {
  auto problem = [](const std::string& key, const std::string& what) { return key + " " + what; };
  auto got = [](double value) { return " (got " + number_text(value) + ")"; };
  c.controller.scheme.reset();
  if (c.controller.code == "auto") {
    if (!(c.optics.electrons > 0) || !(c.optics.read_noise_e > 0) || !(c.optics.cap >= 1))
      return problem("controller.code",
                     "auto needs optics.read_noise_e > 0 (flutterscan calibrate noise) and "
                     "optics.cap >= 1; optics.electrons, if given, > 0");
    if (c.controller.probe_frames < 1 || c.controller.probe_frames > 100)
      return problem("controller.probe_frames",
                     "must be within 1..100" + got(c.controller.probe_frames));
    if (!(c.optics.paper_reflectance > 0 && c.optics.paper_reflectance <= 1))
      return problem("optics.paper_reflectance",
                     "must be within (0, 1]" + got(c.optics.paper_reflectance));
    // Provisional: the session measures the light and chooses again (light_probe.hpp).
    c.controller.scheme =
        codes::choose_scheme(c.optics.electrons, c.optics.read_noise_e, c.optics.cap);
    c.controller.parsed_code = c.controller.scheme->code;
  } else if (auto entry = codes::find_library_code(c.controller.code)) {
    c.controller.parsed_code = codes::to_code(*entry);
  } else if (auto snapshot = codes::snapshot_code(c.controller.code)) {
    c.controller.parsed_code = *snapshot;
  } else {
    auto parsed = LedCode::parse(c.controller.code, 3, CodeRule::kOneOfN);
    if (!parsed.ok())
      return problem("controller.code", "'" + c.controller.code +
                                            "' is neither a library code, a white strobe "
                                            "snapshot-1..52 nor a one-of-3 digit string (slot " +
                                            std::to_string(parsed.error().slot) + ")");
    c.controller.parsed_code = parsed.value();
  }
  if (c.controller.parsed_code.leds() != 3)
    return problem("controller.code", "must be a code of the 3 LEDs");
  if (c.controller.slot_time_us < protocol::kMinSlotTimeUs ||
      c.controller.slot_time_us > protocol::kMaxSlotTimeUs)
    return problem("controller.slot_time_us",
                   "must be within " + std::to_string(protocol::kMinSlotTimeUs) + ".." +
                       std::to_string(protocol::kMaxSlotTimeUs) + got(c.controller.slot_time_us));
  if (c.controller.sync != "slave" && c.controller.sync != "master")
    return problem("controller.sync", "must be slave or master");
  if (c.controller.sync == "master" && c.controller.frame_period_us == 0)
    return problem("controller.frame_period_us", "must be set (> 0) for master sync");
  // The controller takes 0 (unset) or kMinFramePeriodUs..kMaxFramePeriodUs, in any sync mode.
  if (c.controller.frame_period_us != 0 &&
      (c.controller.frame_period_us < protocol::kMinFramePeriodUs ||
       c.controller.frame_period_us > protocol::kMaxFramePeriodUs))
    return outside("controller.frame_period_us", c.controller.frame_period_us,
                   "0 (unset) or " + std::to_string(protocol::kMinFramePeriodUs) + ".." +
                       std::to_string(protocol::kMaxFramePeriodUs) + " us");
  if (!(c.optics.px_per_count > 0))
    return problem("optics.px_per_count", "must be > 0" + got(c.optics.px_per_count));
  // Sizes bounded where they enter (docs/session.md, "Bounds"): a blur is at most
  // imaging::kMaxBlurPx, and a frame's side at most imaging::kMaxFrameSidePx.
  const std::string blur_range = "(0, " + number_text(imaging::kMaxBlurPx) + "] px";
  if (c.optics.px_per_count > kMaxPxPerCount)
    return outside("optics.px_per_count", c.optics.px_per_count,
                   "(0, " + number_text(kMaxPxPerCount) + "]",
                   "one encoder count would move the belt that many pixels (a blur of " +
                       number_text(imaging::kMaxBlurPx) + " px is the most a frame may have)");
  if (!c.optics.encoder && !(c.optics.nominal_blur_px > 0))
    return problem("optics.nominal_blur_px",
                   "must be > 0 when optics.encoder = false (the blur at the line's speed; "
                   "flutterscan calibrate speed measures it)" +
                       got(c.optics.nominal_blur_px));
  if (c.optics.nominal_blur_px < 0 || c.optics.nominal_blur_px > imaging::kMaxBlurPx)
    return outside(
        "optics.nominal_blur_px", c.optics.nominal_blur_px,
        c.optics.encoder ? "[0, " + number_text(imaging::kMaxBlurPx) + "] px" : blur_range);
  for (const auto& [key, side] : {std::pair{"camera.width", c.camera.settings.width},
                                  std::pair{"camera.height", c.camera.settings.height}})
    if (side && (*side < 1 || *side > imaging::kMaxFrameSidePx))
      return outside(key, *side, "1.." + std::to_string(imaging::kMaxFrameSidePx) + " px");
  if (const auto& e = c.camera.settings.exposure_us; e && !(*e > 0 && *e <= 10e6))
    return outside("camera.exposure_us", *e, "(0, 10000000] us");
  if (const auto& g = c.camera.settings.gain_db; g && !(*g >= 0 && *g <= 100))
    return outside("camera.gain_db", *g, "[0, 100] dB");
  if (const auto& f = c.camera.settings.frame_rate_hz; f && !(*f > 0 && *f <= 100000))
    return outside("camera.frame_rate_hz", *f, "(0, 100000] Hz");
  if (!(c.optics.line_time_us >= 0 && c.optics.line_time_us < 1000))
    return problem("optics.line_time_us",
                   "must be 0 (global shutter) up to 1000 us" + got(c.optics.line_time_us));
  if (c.processing.blur_check_every < 0)
    return problem("processing.blur_check_every",
                   "must be >= 0" + got(c.processing.blur_check_every));
  if (!(c.processing.blur_tolerance_pct >= 0 && c.processing.blur_tolerance_pct < 100))
    return problem("processing.blur_tolerance",
                   "must be a percentage >= 0 and < 100 (0: the encoder's blur exactly)" +
                       got(c.processing.blur_tolerance_pct));
  if (auto why = reader::check_symbologies(c.processing.symbologies); !why.empty())
    return problem("processing.symbologies", "'" + c.processing.symbologies + "': " + why);
  imaging::Direction direction;
  if (!imaging::parse_direction(c.optics.direction, direction))
    return problem("optics.direction", "must be +x, -x, +y or -y");
  if (!(c.optics.electrons > 0))
    return problem("optics.electrons", "must be > 0" + got(c.optics.electrons));
  if (!(c.optics.cap > 0)) return problem("optics.cap", "must be > 0" + got(c.optics.cap));
  if (c.optics.bit_depth < 8 || c.optics.bit_depth > 16)
    return problem("optics.bit_depth", "must be within 8..16" + got(c.optics.bit_depth));
  // Electron counts: a pixel holds at most kMaxElectrons (float planes keep them exact enough).
  for (const auto& [key, value] : {std::pair{"optics.electrons", c.optics.electrons},
                                   std::pair{"optics.full_well_e", c.optics.full_well_e}})
    if (!(value >= 1 && value <= kMaxElectrons))
      return outside(key, value, "[1, " + number_text(kMaxElectrons) + "] e-");
  if (!(c.optics.cap >= 0.01 && c.optics.cap <= 1000))  // it scales every LED's light
    return outside("optics.cap", c.optics.cap, "[0.01, 1000]");
  if (!(c.optics.read_noise_e >= 0 && c.optics.read_noise_e <= 10000))
    return outside("optics.read_noise_e", c.optics.read_noise_e, "[0, 10000] e-");
  if (!(c.optics.paper_reflectance > 0 && c.optics.paper_reflectance <= 1))
    return outside("optics.paper_reflectance", c.optics.paper_reflectance, "(0, 1]");
  for (std::size_t i = 0; i < c.optics.crosstalk.size(); ++i)
    if (!(c.optics.crosstalk[i] == 0 || (c.optics.crosstalk[i] >= imaging::kMinCrosstalk &&
                                         c.optics.crosstalk[i] <= kMaxCrosstalk)))
      return outside(
          "optics.crosstalk[" + std::to_string(i / 3) + "][" + std::to_string(i % 3) + "]",
          c.optics.crosstalk[i],
          "0 or [" + number_text(imaging::kMinCrosstalk) + ", " + number_text(kMaxCrosstalk) + "]",
          "a channel's response to an LED, about 0..1");
  const double full_scale_dn = std::pow(2.0, c.optics.bit_depth) - 1;
  if (!(c.optics.black_level_dn >= 0 && c.optics.black_level_dn < full_scale_dn))
    return outside(
        "optics.black_level_dn", c.optics.black_level_dn,
        "[0, " + number_text(full_scale_dn) + ") DN",
        "below the full scale of optics.bit_depth = " + std::to_string(c.optics.bit_depth));
  if (!(c.optics.gain_e_per_dn == 0 ||
        (c.optics.gain_e_per_dn >= 1e-3 && c.optics.gain_e_per_dn <= kMaxElectrons)))
    return outside("optics.gain_e_per_dn", c.optics.gain_e_per_dn,
                   "0 or [0.001, " + number_text(kMaxElectrons) + "] e-/DN",
                   "0 means full well at full scale");
  if (c.processing.workers < 1 || c.processing.workers > 64)
    return problem("processing.workers", "must be within 1..64" + got(c.processing.workers));
  if (!(c.processing.second_pass_ms == -1 ||
        (c.processing.second_pass_ms >= 0 && c.processing.second_pass_ms <= kMaxSecondPassMs)))
    return outside("processing.second_pass_ms", c.processing.second_pass_ms,
                   "\"auto\" or [0, " + number_text(kMaxSecondPassMs) + "] ms per frame",
                   "the cascade's CPU budget for second passes");
  if (!(c.processing.decode_ms == -1 ||
        (c.processing.decode_ms > 0 && c.processing.decode_ms <= kMaxDecodeMs)))
    return outside("processing.decode_ms", c.processing.decode_ms,
                   "\"auto\" or (0, " + number_text(kMaxDecodeMs) + "] ms per frame",
                   "the first pass's decode time");
  if (!(c.processing.latency_ms == -1 ||
        (c.processing.latency_ms > 0 && c.processing.latency_ms <= kMaxLatencyMs)))
    return outside("processing.latency_ms", c.processing.latency_ms,
                   "\"auto\" or (0, " + number_text(kMaxLatencyMs) + "] ms",
                   "each frame's result due after its arrival");
  if (c.processing.threads_per_worker < 1 || c.processing.threads_per_worker > 64)
    return problem("processing.threads_per_worker",
                   "must be within 1..64" + got(c.processing.threads_per_worker));
  if (c.processing.queue_depth < 1 || c.processing.queue_depth > kMaxQueueDepth)
    return outside("processing.queue_depth", static_cast<double>(c.processing.queue_depth),
                   "1.." + std::to_string(kMaxQueueDepth) + " frames",
                   "every waiting frame holds its pixels");
  if (c.processing.max_seconds < 0)
    return problem("processing.max_seconds", "must be >= 0" + got(c.processing.max_seconds));
  if (!(c.processing.match_tolerance_us > 0))
    return problem("processing.match_tolerance_us",
                   "must be > 0" + got(c.processing.match_tolerance_us));
  if (!(c.processing.object_match_px > 0))
    return problem("processing.object_match_px", "must be > 0" + got(c.processing.object_match_px));
  if (c.output.dir.empty()) return problem("output.dir", "must not be empty");
  if (c.output.keep_first_frames < 0)
    return problem("output.keep_first_frames", "must be >= 0" + got(c.output.keep_first_frames));
  if (!(c.output.disk_budget_mb >= 0))
    return problem("output.disk_budget_mb", "must be >= 0" + got(c.output.disk_budget_mb));
  if (c.output.disk_budget_mb > kMaxDiskBudgetMb)  // held in bytes as a 64-bit count
    return outside("output.disk_budget_mb", c.output.disk_budget_mb,
                   "[0, " + number_text(kMaxDiskBudgetMb) + "] MB");
  if (c.results.tcp_port < -1 || c.results.tcp_port > 65535)
    return problem("results.tcp_port",
                   "must be -1 (off), 0 (any) or a port number" + got(c.results.tcp_port));
  if (!c.results.serial.empty() && (c.results.serial_baud < 50 || c.results.serial_baud > 4000000))
    return outside("results.serial_baud", c.results.serial_baud, "50..4000000");
  return {};
}

bool set_processing_method(const std::string& name, ProcessingConfig& processing) {
  if (name == "cascade") {
    processing.method = imaging::Method::kJointWiener;
    processing.cascade = true;
    return true;
  }
  const auto method = imaging::method_from_name(name);
  if (!method) return false;
  processing.method = *method;
  processing.cascade = false;
  return true;
}

std::string processing_method_name(const ProcessingConfig& processing) {
  return processing.cascade ? "cascade" : imaging::method_name(processing.method);
}

}  // namespace flutterscan::session
