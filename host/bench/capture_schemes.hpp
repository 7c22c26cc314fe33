#pragma once
// The capture schemes the accuracy benchmarks compare at one light budget
// (docs/conventions.md, "Light level E and the cap c"): every LED may emit at most E per exposure and
// at most c E / L in a slot. A scheme is an LED pattern over L = 52 slots;
// the light each LED gets follows from the budget.

#include <string>
#include <vector>

#include "flutterscan/common/led_code.hpp"
#include "imaging/capture_model.hpp"

namespace flutterscan::bench {

struct CaptureScheme {
  std::string name;
  LedCode code;       ///< three LEDs; digit 7 lights all three (white)
  bool one_of_three;  ///< a one-of-3 code (every slot one LED)
};

/// \brief rect-white, raskar-white, complement-pair (Raskar on red, its
/// complement on green and blue), the seed's triplets, the best found
/// triplets, contiguous thirds, and white snapshots of 1, 2, 4, 8 and 17 slots.
std::vector<CaptureScheme> standard_schemes();

/// \brief The bench's camera: 12 bits, full well 12000 e-, gain full well / 4095,
/// black level 64 DN, the crosstalk matrix, read noise as given.
imaging::CaptureModel bench_camera(const CaptureScheme& scheme, double electrons, double cap,
                                   double read_noise, double blur_px);

}  // namespace flutterscan::bench
