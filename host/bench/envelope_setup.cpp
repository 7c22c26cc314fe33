#include "bench/envelope_setup.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "bench/real_print_session.hpp"
#include "codes/library.hpp"
#include "codes/scheme_choice.hpp"

namespace flutterscan::bench {

std::vector<EnvelopeSymbol> datasheet_symbols() {
  using sim::SceneKind;
  return {
      {"Code 128 7.5 mil", SceneKind::kCode128, 7.5},
      {"Code 128 10 mil", SceneKind::kCode128, 10},
      {"Code 128 13 mil", SceneKind::kCode128, 13},
      {"Code 128 20 mil", SceneKind::kCode128, 20},
      {"Data Matrix 10 mil", SceneKind::kDataMatrix, 10},
      {"Data Matrix 15 mil", SceneKind::kDataMatrix, 15},
  };
}

double module_px(double mil, const LineSetup& line) {
  return mil * 0.0254 / line.mm_per_px;
}

double exposure_blur_px(double speed_m_s, const LineSetup& line) {
  return speed_m_s * line.slots * line.slot_ms / line.mm_per_px;
}

double speed_for_motion(double px, double ms, const LineSetup& line) {
  return px * line.mm_per_px / ms;
}

double exposure_electrons(double electrons_per_ms, const LineSetup& line) {
  return electrons_per_ms * line.slots * line.slot_ms;
}

CaptureScheme coded_scheme() {
  return {"coded", codes::to_code(*codes::find_library_code("seed-maxmin-1")), true};
}

CaptureScheme strobe_scheme(int slots) {
  return {"strobe-" + std::to_string(slots),
          *codes::snapshot_code("snapshot-" + std::to_string(slots)), false};
}

Lighting coded_of_slot(const LineSetup& line, double slot_us) {
  Lighting out{line, coded_scheme()};
  out.line.slot_ms = slot_us / 1000;
  return out;
}

Lighting strobe_of_pulse(const LineSetup& line, double pulse_us) {
  Lighting out{line, {}};
  const double slot_us = line.slot_ms * 1000;
  int slots = 1;
  if (pulse_us <= slot_us)
    out.line.slot_ms = pulse_us / 1000;
  else
    slots = std::clamp(static_cast<int>(std::lround(pulse_us / slot_us)), 1, line.slots);
  out.scheme = strobe_scheme(slots);
  return out;
}

imaging::CaptureModel line_capture(const CaptureScheme& scheme, const LineSetup& line,
                                   double electrons_per_ms, double speed_m_s) {
  return bench_camera(scheme, exposure_electrons(electrons_per_ms, line), line.cap, line.read_noise,
                      exposure_blur_px(speed_m_s, line));
}

LinePath line_path(const CaptureScheme& scheme, const LineSetup& line, double electrons_per_ms,
                   const LineProcessing& processing) {
  LinePath path{
      line_config(exposure_electrons(electrons_per_ms, line), reader::ReaderOptions{}.area, {}, -1),
      processing.fps};
  session::SessionConfig& c = path.config;
  if (scheme.one_of_three) {
    std::string digits(static_cast<std::size_t>(scheme.code.length()), '0');
    scheme.code.format(digits);
    c.controller.code = digits;
  } else {
    c.controller.code = "snapshot-" + std::to_string(lit_run_slots(scheme));
    if (codes::snapshot_code(c.controller.code) != scheme.code)
      throw std::invalid_argument(scheme.name + " is neither one-of-3 nor a white strobe");
  }
  c.controller.slot_time_us = static_cast<std::uint32_t>(std::lround(line.slot_ms * 1000));
  c.optics.cap = line.cap;
  c.optics.read_noise_e = line.read_noise;
  c.processing.workers = processing.workers;
  if (!session::set_processing_method(processing.method, c.processing))
    throw std::invalid_argument("processing method '" + processing.method + "' is none of " +
                                session::kProcessingMethods);
  return path;
}

int lit_run_slots(const CaptureScheme& scheme) {
  if (scheme.one_of_three) return 1;
  int longest = 0, run = 0;
  for (int t = 0; t < scheme.code.length(); ++t) {
    run = scheme.code.mask(t) != 0 ? run + 1 : 0;
    longest = std::max(longest, run);
  }
  return longest;
}

}  // namespace flutterscan::bench
