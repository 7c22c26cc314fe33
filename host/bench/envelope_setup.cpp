#include "bench/envelope_setup.hpp"

#include <algorithm>

#include "codes/library.hpp"

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
  std::string digits(52, '0');
  for (int t = 0; t < std::min(slots, 52); ++t) digits[static_cast<std::size_t>(t)] = '7';
  return {"strobe-" + std::to_string(slots), LedCode::parse(digits, 3).value(), false};
}

imaging::CaptureModel line_capture(const CaptureScheme& scheme, const LineSetup& line,
                                   double electrons_per_ms, double speed_m_s) {
  return bench_camera(scheme, exposure_electrons(electrons_per_ms, line), line.cap, line.read_noise,
                      exposure_blur_px(speed_m_s, line));
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
