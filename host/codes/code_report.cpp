#include "codes/code_report.hpp"

#include <algorithm>
#include <cstdio>

#include "codes/library.hpp"

namespace flutterscan::codes {
namespace {

struct SeedJoint {
  double value = 0;
  std::string name;
};

SeedJoint best_seed_joint(const MeritSettings& settings) {
  SeedJoint best;
  for (const auto& entry : code_library()) {
    if (!entry.seed_triplet) continue;
    const auto value = evaluate_merit(Merit::kJoint, to_code(entry), settings);
    if (value.ok() && value.value() > best.value) best = {value.value(), std::string(entry.name)};
  }
  return best;
}

std::string printf_string(const char* format, auto... args) {
  char buffer[256];
  std::snprintf(buffer, sizeof buffer, format, args...);
  return buffer;
}

std::string db_text(double db) {
  return db <= kNullDb ? std::string("    null   ") : printf_string("%8.3f dB", db);
}

std::string merit_value_text(Merit merit, double value) {
  switch (merit) {
    case Merit::kMaxMin:
    case Merit::kAvgMin:
    case Merit::kPairs:
      return printf_string("%.4f dB", value);
    case Merit::kSingle:
      return printf_string("%.5f", value);
    case Merit::kJoint:
      return printf_string("%.2f e-", value);
    case Merit::kMse:
      return printf_string("%.6f", value);
  }
  return "";
}

}  // namespace

std::string format_code(const LedCode& code) {
  std::string text(static_cast<std::size_t>(code.length()), '?');
  code.format(text);
  return text;
}

CodeReport make_code_report(const LedCode& code, std::span<const Merit> merits,
                            const MeritSettings& settings) {
  CodeReport report;
  report.code = code;
  for (const auto& entry : code_library())
    if (entry.digits == format_code(code) && entry.leds == code.leds()) report.name = entry.name;
  for (int k = 0; k < code.leds(); ++k) {
    const auto sequence = led_sequence(code, k);
    LedReport led;
    led.led = k;
    led.on_slots = code.on_slots(k);
    led.duty_cycle = code.duty_cycle(k);
    const auto seed = seed_grid_spectrum(sequence);
    led.seed_grid_min_db = *std::min_element(seed.db.begin(), seed.db.end());
    led.dense_min_db = dense_minimum_db(sequence, settings.dense_points);
    const auto circular = circular_spectrum(sequence);
    led.circular_min_db = *std::min_element(circular.db.begin(), circular.db.end());
    report.leds.push_back(led);
  }
  for (Merit merit : merits) {
    MeritReport entry{merit, std::nullopt, {}};
    const auto value = evaluate_merit(merit, code, settings);
    if (value.ok())
      entry.value = value.value();
    else
      entry.inapplicable = value.error();
    report.merits.push_back(entry);
    // The seed's triplets have 52 slots: a ratio to them means something only at that length.
    if (merit == Merit::kJoint && value.ok() && code.length() == 52) {
      const SeedJoint seed = best_seed_joint(settings);
      if (seed.value > 0) {
        report.joint_ratio_to_best_seed = value.value() / seed.value;
        report.best_seed_triplet = seed.name;
      }
    }
  }
  return report;
}

nlohmann::json to_json(const CodeReport& report, const MeritSettings& settings) {
  nlohmann::json out;
  out["code"] = format_code(report.code);
  if (!report.name.empty()) out["name"] = report.name;
  out["leds"] = report.code.leds();
  out["length"] = report.code.length();
  out["one_of_n"] = report.code.is_one_of_n();
  nlohmann::json leds = nlohmann::json::array();
  for (const auto& led : report.leds) {
    leds.push_back({
        {"led", led.led},
        {"on_slots", led.on_slots},
        {"duty_cycle", led.duty_cycle},
        {"seed_grid_min_db", led.seed_grid_min_db},
        {"dense_min_db",
         {{"grid", led.dense_min_db.grid_value},
          {"refined", led.dense_min_db.refined_value},
          {"frequency", led.dense_min_db.refined_frequency}}},
        {"circular_min_db", led.circular_min_db},
    });
  }
  out["per_led"] = leds;
  nlohmann::json merits = nlohmann::json::object();
  for (const auto& merit : report.merits) {
    const std::string name(merit_name(merit.merit));
    if (merit.value)
      merits[name] = *merit.value;
    else
      merits[name] = nullptr;
  }
  out["merits"] = merits;
  if (report.joint_ratio_to_best_seed) {
    out["joint_ratio_to_best_seed"] = *report.joint_ratio_to_best_seed;
    out["best_seed_triplet"] = report.best_seed_triplet;
  }
  const auto& light = settings.light;
  out["settings"] = {{"electrons", light.electrons},
                     {"cap", light.cap},
                     {"read_noise", light.read_noise},
                     {"mse_eps", settings.mse_eps},
                     {"single_pad", settings.single_pad},
                     {"dense_points", settings.dense_points},
                     {"crosstalk", light.crosstalk ? nlohmann::json(light.crosstalk->gain)
                                                   : nlohmann::json(nullptr)}};
  return out;
}

std::string to_text(const CodeReport& report, const MeritSettings& settings) {
  const LedCode& code = report.code;
  std::string out = format_code(code);
  if (!report.name.empty()) out += "  (" + report.name + ")";
  out += printf_string(
      "\n  %d LED%s, %d slots%s\n", code.leds(), code.leds() == 1 ? "" : "s", code.length(),
      code.leds() > 1 && code.is_one_of_n() ? printf_string(", one-of-%d", code.leds()).c_str()
                                            : "");
  out += "  LED  on  duty   seed-grid min   linear-blur min (grid / refined @ f)   circular min\n";
  for (const auto& led : report.leds) {
    out +=
        printf_string("  %-3d  %-3d %5.1f%%  %s     %s / %s @ %.4f     %s\n", led.led, led.on_slots,
                      100.0 * led.duty_cycle, db_text(led.seed_grid_min_db).c_str(),
                      db_text(led.dense_min_db.grid_value).c_str(),
                      db_text(led.dense_min_db.refined_value).c_str(),
                      led.dense_min_db.refined_frequency, db_text(led.circular_min_db).c_str());
  }
  for (const auto& merit : report.merits) {
    out += printf_string("  %-7s ", std::string(merit_name(merit.merit)).c_str());
    if (!merit.value) {
      out += "n/a (" + merit.inapplicable + ")\n";
      continue;
    }
    out += merit_value_text(merit.merit, *merit.value);
    if (merit.merit == Merit::kJoint) {
      const auto& light = settings.light;
      out += printf_string("  (E %g e-, cap %g, read noise %g e-%s)", light.electrons, light.cap,
                           light.read_noise, light.crosstalk ? ", crosstalk" : "");
      if (report.joint_ratio_to_best_seed)
        out += printf_string(", %.2fx %s", *report.joint_ratio_to_best_seed,
                             report.best_seed_triplet.c_str());
    }
    out += "\n";
  }
  return out;
}

}  // namespace flutterscan::codes
