#pragma once
// Forward models beyond sim::expected_electrons (docs/conventions.md, "The forward model"):
// - an explicit exposure timeline (imaging/exposure_timeline.hpp), e.g. a belt
//   speed that varies within the exposure (sim/speed_profile.hpp);
// - colour objects: one reflectance plane per LED band; channel c records
//   sum_k M[c][k] (h_k * r_k) + a_c (rect * r_c), so a red print that is dark
//   under the green and blue LEDs is almost white under the red one;
// - rolling-shutter readout: row r starts r * line_time later and the
//   controller repeats the pattern cyclically over the frame, so the row sees
//   the code from phase r * line_time / slot_time (modulo L, fractional slots
//   exact). Each row's latent is registered at the object's position at the
//   start of that row's exposure (the readout's geometric skew is left out:
//   it moves rows, it does not blur them).
// All return expected electrons; sim::record_frame() adds the noise.

#include <span>
#include <string>

#include "flutterscan/common/result.hpp"
#include "imaging/capture_model.hpp"
#include "imaging/exposure_timeline.hpp"
#include "imaging/image.hpp"

namespace flutterscan::sim {

/// \brief Expected electrons of a grey scene when every row sees `segments`
/// (camera pixels of motion), the scene rendered `supersample` times finer
/// than the camera's pixels as for sim::expected_electrons(). The model's own
/// slot_segments() give sim::expected_electrons() (same arithmetic).
imaging::Image expected_electrons_timeline(const imaging::Plane& reflectance,
                                           const imaging::CaptureModel& model,
                                           std::span<const imaging::ExposureSegment> segments,
                                           int supersample = 1);

/// \brief Code phase in slots of rolling-shutter row `row`: row * line_time /
/// slot_time modulo `slots` (line_time and slot_time in the same unit).
double rolling_shutter_phase(int row, double line_time, double slot_time, int slots);

/// \brief Expected electrons of a grey scene read out by a rolling shutter:
/// row r of the image sees cyclic_phase_segments(model, rolling_shutter_phase(r, ...)).
/// Fails unless the motion is along x (rows of the image must be rows of the
/// motion) and both times are finite with slot_time > 0 and line_time >= 0.
Result<imaging::Image, std::string> expected_rolling_shutter_electrons(
    const imaging::Plane& reflectance, const imaging::CaptureModel& model, double line_time,
    double slot_time);

/// \brief Expected electrons of a colour scene: `bands[k]` is the reflectance
/// under LED k (equal sizes). Needs 3 channels and 3 LEDs; the ambient light
/// of channel c falls on band c. With three equal bands it equals
/// sim::expected_electrons() of that band to float rounding. `supersample` as
/// for sim::expected_electrons().
Result<imaging::Image, std::string> expected_colour_electrons(std::span<const imaging::Plane> bands,
                                                              const imaging::CaptureModel& model,
                                                              int supersample = 1);

/// \brief The same when every row sees `segments` (camera pixels of motion):
/// a belt whose motion departs from the model's constant speed (jitter, a
/// scene that moves in whole-pixel steps), as expected_electrons_timeline()
/// gives it for a grey scene. The model's own slot_segments() give
/// expected_colour_electrons().
Result<imaging::Image, std::string> expected_colour_electrons_timeline(
    std::span<const imaging::Plane> bands, const imaging::CaptureModel& model,
    std::span<const imaging::ExposureSegment> segments, int supersample = 1);

}  // namespace flutterscan::sim
