#include "bench/capture_schemes.hpp"

#include "codes/library.hpp"
#include "codes/scheme_choice.hpp"

namespace flutterscan::bench {
namespace {

constexpr int kSlots = 52;

LedCode library_code(const char* name) {
  return codes::to_code(*codes::find_library_code(name));
}

CaptureScheme snapshot(int slots) {
  const std::string name = "snapshot-" + std::to_string(slots);
  return {name, *codes::snapshot_code(name), false};
}

}  // namespace

std::vector<CaptureScheme> standard_schemes() {
  std::vector<CaptureScheme> schemes = {
      {"rect-white", library_code("rect-white"), false},
      {"raskar-white", library_code("raskar-white"), false},
  };
  // Raskar's code on red, its complement on green and blue: a pair in one exposure.
  LedCode pair = library_code("raskar-white");
  const LedCode raskar = library_code("raskar");
  for (int t = 0; t < kSlots; ++t) pair.set_mask(t, raskar.is_on(t, 0) ? 1 : 6);
  schemes.push_back({"complement-pair", pair, false});
  for (const char* name : {"seed-maxmin-1", "seed-maxmin-3", "seed-avgmin", "seed-pairs",
                           "found-joint", "found-mse", "thirds"})
    schemes.push_back({name, library_code(name), true});
  for (int slots : {1, 2, 4, 8, 17}) schemes.push_back(snapshot(slots));
  return schemes;
}

imaging::CaptureModel bench_camera(const CaptureScheme& scheme, double electrons, double cap,
                                   double read_noise, double blur_px) {
  imaging::CaptureModel m;
  m.code = scheme.code;
  m.blur_px = blur_px;
  m.crosstalk = {0.90, 0.08, 0.01, 0.10, 0.85, 0.12, 0.01, 0.07, 0.88};
  m.led_electrons = imaging::budgeted_led_electrons(scheme.code, electrons, cap);
  m.read_noise = read_noise;
  m.full_well = 12000;
  m.bit_depth = 12;
  m.gain = m.full_well / 4095.0;
  m.black_level = 64;
  return m;
}

}  // namespace flutterscan::bench
