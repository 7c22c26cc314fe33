#pragma once
// Tests only: the capture model the imaging, sim and session tests share, the
// design's reference camera (crosstalk M, read noise 4 e-, 12 bits over a
// 12000 e- well) and a label on it under a one-of-3 code at cap 3, each test
// changing what it studies.

#include "imaging/capture_model.hpp"

namespace flutterscan::test_fixtures {

/// The library's found-mse triplet (codes/library.cpp).
inline constexpr const char* kFoundMse = "4242221144411121214241142422112112214412414144224412";

/// What a test changes of the reference capture.
struct LabelCapture {
  const char* code = kFoundMse;  ///< one-of-3 digits
  double blur_px = 52;
  double electrons = 3000;  ///< per channel (E), budgeted at cap 3
  imaging::Direction direction = imaging::Direction::kPlusX;
  double black_level = 0;  ///< DN
};

/// \brief The reference camera alone (no code, no light): crosstalk M = [[0.90, 0.08, 0.01],
/// [0.10, 0.85, 0.12], [0.01, 0.07, 0.88]], read noise 4 e-, full well 12000 e-, 12 bits
/// (gain 12000 / 4095 e- per DN), black level `black_level` DN.
inline imaging::CaptureModel reference_camera(double black_level = 0) {
  imaging::CaptureModel m;
  m.crosstalk = {0.90, 0.08, 0.01, 0.10, 0.85, 0.12, 0.01, 0.07, 0.88};
  m.read_noise = 4;
  m.full_well = 12000;
  m.bit_depth = 12;
  m.gain = 12000.0 / 4095.0;
  m.black_level = black_level;
  return m;
}

/// \brief The reference capture with `o`'s changes: the reference camera, the LEDs
/// budgeted to `o.electrons` at cap 3.
inline imaging::CaptureModel label_capture(const LabelCapture& o = {}) {
  imaging::CaptureModel m = reference_camera(o.black_level);
  m.code = LedCode::parse(o.code, 3).value();
  m.blur_px = o.blur_px;
  m.direction = o.direction;
  m.led_electrons = imaging::budgeted_led_electrons(m.code, o.electrons, 3);
  return m;
}

}  // namespace flutterscan::test_fixtures
