#pragma once
// The line the datasheet (docs/datasheet.md) is measured on: the optics (one
// pixel's size on the belt), the controller's slot time, the light (electrons a
// pixel of white paper collects per millisecond at the LEDs' continuous
// rating), the camera, and the two capture schemes compared: the product's coded
// one-of-3 light and a white strobe of k slots under the same light budget
// (docs/conventions.md, "Light level E and the cap c").

#include <string>
#include <vector>

#include "bench/capture_schemes.hpp"
#include "bench/line_labels.hpp"
#include "imaging/capture_model.hpp"
#include "sim/scene.hpp"

namespace flutterscan::bench {

/// \brief The optics, timing and camera of the datasheet.
struct LineSetup {
  double mm_per_px = 0.1;  ///< one camera pixel on the belt
  double slot_ms = 0.1;    ///< the controller's slot time (100 us: the session's default)
  int slots = 52;          ///< slots per exposure: the exposure is slots x slot_ms
  double cap = 3;          ///< LED overdrive cap c
  double read_noise = 4;   ///< camera read noise, e- rms (the bench camera otherwise)
};

/// \brief How the line's session processes its frames.
struct LineProcessing {
  std::string method = "cascade";  ///< processing.method (session::kProcessingMethods)
  double fps = 30;                 ///< the camera's frame rate (0: unknown, as offline)
  int workers = 2;                 ///< processing.workers
};

/// \brief A symbol of the datasheet: a symbology at one X dimension (mil).
struct EnvelopeSymbol {
  std::string name;  ///< e.g. "Code 128 10 mil"
  sim::SceneKind kind = sim::SceneKind::kCode128;
  double mil = 10;
};

/// \brief Code 128 at 7.5, 10, 13 and 20 mil; Data Matrix at 10 and 15 mil.
std::vector<EnvelopeSymbol> datasheet_symbols();

/// \brief One module in camera pixels: mil x 0.0254 mm / mm_per_px.
double module_px(double mil, const LineSetup& line);

/// \brief The belt's travel during one exposure in pixels at `speed_m_s`
/// (m/s = mm/ms): speed x slots x slot_ms / mm_per_px.
double exposure_blur_px(double speed_m_s, const LineSetup& line);

/// \brief The belt speed (m/s) that moves `px` pixels in `ms` milliseconds.
double speed_for_motion(double px, double ms, const LineSetup& line);

/// \brief E of docs/conventions.md: electrons per channel of white paper over the
/// exposure with every LED at its continuous rating: `electrons_per_ms` x exposure.
double exposure_electrons(double electrons_per_ms, const LineSetup& line);

/// \brief The product's coded one-of-3 light: the session's default code
/// (controller.code, seed-maxmin-1).
CaptureScheme coded_scheme();

/// \brief A white strobe of `slots` slots (all LEDs, at the cap), the regime
/// map's snapshot-k.
CaptureScheme strobe_scheme(int slots);

/// \brief The coded light's slot times the datasheet searches, us: the line picks
/// its slot (52 of them make an exposure of 1.3 to 20.8 ms, within a 30 fps frame).
inline constexpr double kCodedSlotsUs[] = {25, 50, 100, 200, 400};

/// \brief The white strobe pulses the datasheet searches, us: the line picks its pulse.
inline constexpr double kStrobePulsesUs[] = {25, 50, 100, 200, 400, 800};

/// \brief How a line is lit: the line with its slot time, and the scheme.
struct Lighting {
  LineSetup line;
  CaptureScheme scheme;
};

/// \brief The product's coded light (coded_scheme()) with slots of `slot_us` on `line`.
Lighting coded_of_slot(const LineSetup& line, double slot_us);

/// \brief The white strobe of `pulse_us` on `line`: one slot of that length where
/// the pulse is no longer than the line's slot, else the line's slot time and
/// the pulse rounded to whole slots. Its light depends on the pulse alone (c
/// times the continuous rating for the pulse: docs/conventions.md's budget), not
/// on how it is cut into slots.
Lighting strobe_of_pulse(const LineSetup& line, double pulse_us);

/// \brief The capture model of `scheme` on `line` at `speed_m_s` and
/// `electrons_per_ms`: the bench camera (capture_schemes.hpp) with the line's
/// read noise, cap and exposure, motion along +x, constant speed.
imaging::CaptureModel line_capture(const CaptureScheme& scheme, const LineSetup& line,
                                   double electrons_per_ms, double speed_m_s);

/// \brief The session a line lit by `scheme` runs on `line` at `electrons_per_ms`:
/// the session's default config with the scheme's code, the line's slot time,
/// light (E), cap and read noise, processed as `processing` says. Throws if the
/// method is none of session::kProcessingMethods, or the scheme is neither
/// one-of-3 nor a white strobe (controller.code snapshot-K).
LinePath line_path(const CaptureScheme& scheme, const LineSetup& line, double electrons_per_ms,
                   const LineProcessing& processing);

/// \brief The stretch of the exposure, in slots, within which the light cannot
/// tell positions apart: one slot for a code that changes LEDs every slot (every
/// LED's light comes in boxes of one slot's motion, on one slot grid), k for a
/// k-slot strobe. Its motion is the blur no deconvolution undoes.
int lit_run_slots(const CaptureScheme& scheme);

}  // namespace flutterscan::bench
