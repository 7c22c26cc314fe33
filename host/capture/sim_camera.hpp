#pragma once
// "sim": a virtual conveyor under a virtual camera. Labels of mixed kinds
// (Code 128, EAN-13, QR, Data Matrix) ride a belt past the camera at a set
// speed (optionally jittered frame to frame). Each frame is one strobe pulse
// into the virtual controller (slave mode): the light that reaches the scene
// is the controller's ACTUAL LED transitions during it, turned back into a
// per-slot code, and the belt's motion goes to the controller's encoder, so
// exposure events carry the true encoder delta. The frame is rendered through
// host/sim's forward model (crosstalk, EMVA 1288 noise) as 16-bit RGB DN.
//
// Geometry: the belt (plain, or printed all over: option belt) moves toward +x; label i (0 first)
// starts at belt coordinate -(i + 1) * pitch and is `tile_width` wide; image column x shows belt
// coordinate x - travel, travel being the belt's motion since start.
//
// Ground truth (Frame::truth): the labels a deblur can recover whole, whose
// tile stays in view through the exposure and starts at least one blur
// length from the upstream edge.
//
// Static target (option target=white[:REFLECTANCE], for `flutterscan calibrate`):
// the belt stands still under a flat white card (reflectance 0.9 unless given),
// lit by the same actual LED transitions through the same forward model,
// crosstalk, noise and black level; the encoder does not turn. `falloff` makes
// the light fall off toward the corners (1 - falloff * r^2, r = 1 at a corner),
// as a real LED head does, for the flat-field calibration.
//
// True values a calibration should recover (sim_truth): the crosstalk matrix,
// black_level, gain = full_well / (2^bit_depth - 1) e-/DN, read_noise e-,
// px per encoder count = 1 / counts_per_px.
//
// Camera clock: timestamp_ns = offset_ns + controller_us * 1000 * (1 + drift_ppm
// 1e-6) at the start of the strobe; sequence numbers count from 0 and include
// frames lost on the way (drop_probability), as a V4L2 sequence does.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "capture/camera_source.hpp"
#include "imaging/capture_model.hpp"

namespace flutterscan::capture {

struct SimConveyorOptions {
  int width = 960;
  int height = 360;
  int tile_width = 420;            ///< belt length a label's tile takes, px
  int gap = 120;                   ///< belt between tiles, px
  double speed_px_per_s = 10'000;  ///< belt speed seen by the camera
  double jitter = 0;               ///< relative rms speed change from frame to frame
  double counts_per_px = 2;        ///< encoder counts per pixel of belt travel
  std::uint32_t frame_period_us = 16'667;
  std::uint32_t exposure_us = 6'000;  ///< strobe pulse width
  double electrons = 3000;            ///< E: e- per channel of white under rect-white
  double cap = 3;                     ///< overdrive cap
  double read_noise = 4;
  double full_well = 12000;
  int bit_depth = 12;
  double black_level = 64;
  std::vector<double> crosstalk = {0.90, 0.08, 0.01, 0.10, 0.85, 0.12, 0.01, 0.07, 0.88};
  double drop_probability = 0;  ///< frames exposed but lost before the host
  std::int64_t clock_offset_ns = 1'000'000'000;
  double clock_drift_ppm = 40;
  std::uint64_t seed = 1;
  std::uint64_t max_frames = 0;  ///< 0: unlimited; then kEnd
  bool pace_realtime = false;    ///< deliver at most one frame per frame period of host time
  /// Frames rendered once and replayed cyclically (0: render every frame);
  /// needs jitter 0. For benchmarks: rendering cost stays out of the pipeline.
  /// Rendered at start() from the first exposure; each frame is still exposed
  /// (its event queued on the controller) when it is delivered.
  int ring_frames = 0;
  /// Frames rendered at once (exposures run that far ahead of delivery).
  int render_threads = 2;
  /// "labels" (the conveyor) or "white[:REFLECTANCE]" (a static white card).
  std::string target = "labels";
  /// The belt between the labels: "plain" (reflectance 0.35) or "print": lines
  /// of text in every row, of three sizes, dark on the belt's brown, moving with
  /// it (a printed carton's sides; no code in them).
  std::string belt = "plain";
  /// Static target only: relative light lost at the frame's corners (0..0.9).
  double falloff = 0;
};

/// \brief The simulator's true calibration: what `flutterscan calibrate` should find.
struct SimTruth {
  std::vector<double> crosstalk;  ///< 3x3 row-major, as configured (columns not normalised)
  double black_level_dn = 0;
  double gain_e_per_dn = 0;  ///< full_well / (2^bit_depth - 1)
  double read_noise_e = 0;
  double px_per_count = 0;  ///< 1 / counts_per_px
};

/// The most encoder counts per pixel of belt travel the sim takes.
inline constexpr double kMaxSimCountsPerPx = 10000;
/// The most memory ring_frames may take, bytes.
inline constexpr double kMaxSimRingBytes = 2e9;

/// \brief The first option out of its range, naming the option, its value and the
/// range (empty if none): checked when the camera is made, so a bad option is bad
/// input, and again by open() after configure() (camera.width, exposure, rate).
std::string sim_options_problem(const SimConveyorOptions& options);

/// \brief The true values behind `options`.
SimTruth sim_truth(const SimConveyorOptions& options);

/// \brief The static target's reflectance for `target` ("white" = 0.9, "white:R"),
/// or -1 for "labels"; the error names a malformed target.
std::string parse_sim_target(const std::string& target, double& reflectance);

/// \brief Reads key=value options (the names of SimConveyorOptions' members);
/// the error names the key or the value.
std::string apply_sim_options(const std::vector<std::pair<std::string, std::string>>& options,
                              SimConveyorOptions& sim);

/// \brief The sim camera on `controller` (which must outlive it).
std::unique_ptr<CameraSource> make_sim_camera(device::VirtualController& controller,
                                              const SimConveyorOptions& options);

/// \brief The ground-truth content of label `index` (cycling through the four kinds).
std::string sim_label_scene(std::uint64_t index);

}  // namespace flutterscan::capture
