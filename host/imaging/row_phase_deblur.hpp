#pragma once
// The per-row code phase model for rolling-shutter cameras (only rolling-shutter
// cameras need a per-row code phase). The controller repeats
// the pattern cyclically over the frame, so image row r saw the code from its
// own phase (sim::rolling_shutter_phase: r * line_time / slot_time modulo L).
// Rows are grouped by their phase quantised to `phase_step` slots; each group
// is one deconvolution problem with that phase's PSFs
// (cyclic_phase_segments), solved by the method asked for on the group's
// rows stacked in order. For joint Wiener and rl rows are independent, so
// this is exact up to the quantisation; tv's across-row prior then links
// consecutive rows of a group, which are neighbours in the image only when
// the phase changes slowly from row to row (say so where tv is charted).

#include <span>
#include <string>

#include "flutterscan/common/result.hpp"
#include "imaging/capture_model.hpp"
#include "imaging/deblur.hpp"
#include "imaging/motion_frame.hpp"

namespace flutterscan::imaging {

/// \brief Default phase quantum: 1/8 slot (a shift of blur / (8 L) pixels, 0.125 px at 52 px).
inline constexpr double kRowPhaseStep = 0.125;

/// \brief The finest phase quantum deblur_row_phases takes, slots.
inline constexpr double kMinRowPhaseStep = 1e-6;

/// \brief Deblurs a rolling-shutter frame whose image row r (line r of the
/// motion frame: motion along x) saw the code from `row_phase_slots[r]` (taken
/// modulo the code's length). Returns the grey latent (reflectance, in the
/// motion frame). Errors: those of deblur() (the model's own checks,
/// image_checks.hpp, and a blur that does not fit the row), a phase count other
/// than the frame's lines, a non-finite phase, phase_step outside
/// [kMinRowPhaseStep, 1].
Result<Plane, std::string> deblur_row_phases(const MotionFrame& frame, const CaptureModel& model,
                                             std::span<const double> row_phase_slots,
                                             const DeblurOptions& options,
                                             double phase_step = kRowPhaseStep);

}  // namespace flutterscan::imaging
