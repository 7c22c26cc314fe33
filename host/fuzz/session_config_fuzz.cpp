// libFuzzer target: the session config (TOML text) through parse_config and
// check_config (host/session/session_config.hpp). Oracles: a refusal names the
// file (parse) or the key (check); an accepted config holds every size within
// its stated bound (docs/session.md, "Bounds").

#include <cmath>
#include <string>

#include "fuzz_support.hpp"
#include "imaging/limits.hpp"
#include "session/session_config.hpp"

using namespace flutterscan;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size > 64 * 1024) return 0;
  const std::string text(reinterpret_cast<const char*>(data), size);
  auto parsed = session::parse_config(text, "fuzz.toml");
  if (!parsed.ok()) {
    fuzz::trace("parse: " + parsed.error());
    FUZZ_CHECK(parsed.error().rfind("fuzz.toml", 0) == 0,
               "parse error without the file: " + parsed.error());
    return 0;
  }
  session::SessionConfig config = parsed.value();
  const std::string problem = session::check_config(config);
  if (!problem.empty()) {
    fuzz::trace("check: " + problem);
    bool names_a_key = false;
    for (const char* section :
         {"camera.", "controller.", "optics.", "processing.", "output.", "results."})
      names_a_key |= problem.rfind(section, 0) == 0;
    FUZZ_CHECK(names_a_key, "refusal that names no key: " + problem);
    return 0;
  }
  const auto& o = config.optics;
  FUZZ_CHECK(o.px_per_count > 0 && o.px_per_count <= session::kMaxPxPerCount,
             std::to_string(o.px_per_count));
  FUZZ_CHECK(o.nominal_blur_px >= 0 && o.nominal_blur_px <= imaging::kMaxBlurPx,
             std::to_string(o.nominal_blur_px));
  FUZZ_CHECK(o.electrons >= 1 && o.electrons <= session::kMaxElectrons, "electrons");
  FUZZ_CHECK(o.full_well_e >= 1 && o.full_well_e <= session::kMaxElectrons, "full well");
  FUZZ_CHECK(std::isfinite(o.black_level_dn) && o.black_level_dn >= 0, "black level");
  const auto& p = config.processing;
  FUZZ_CHECK(p.queue_depth >= 1 && p.queue_depth <= session::kMaxQueueDepth, "queue depth");
  FUZZ_CHECK(
      p.workers >= 1 && p.workers <= 64 && p.threads_per_worker >= 1 && p.threads_per_worker <= 64,
      "workers");
  for (const auto& side : {config.camera.settings.width, config.camera.settings.height})
    FUZZ_CHECK(!side || (*side >= 1 && *side <= imaging::kMaxFrameSidePx), "camera side");
  FUZZ_CHECK(
      config.controller.parsed_code.leds() == 3 && config.controller.parsed_code.length() > 0,
      "code");
  FUZZ_CHECK(config.output.disk_budget_mb >= 0 &&
                 config.output.disk_budget_mb <= session::kMaxDiskBudgetMb,
             "disk budget");
  return 0;
}
