#pragma once
// Labels passing a line camera, one frame each, through the session's per-frame
// path (docs/datasheet.md, "The line measured"): a label of one symbol at one module
// size, on the belt, under continuous motion with belt jitter, a speed change
// within the exposure and an encoder that tells the blur a little wrong;
// recorded with EMVA 1288 noise by the camera the line's session config
// describes; read by session::process_frame with that config (model choice,
// guards, the encoder's blur refined on the frame, the deblur, the decode and
// the cascade's second pass within the budget the line's frame rate gives).
// Each label number draws its own content, sub-pixel position, motion and noise.

#include <cstdint>
#include <string>
#include <vector>

#include "imaging/image.hpp"
#include "session/session_config.hpp"
#include "sim/scene.hpp"

namespace flutterscan::bench {

/// \brief What the line does to the motion, per label.
struct LineMotion {
  double jitter_rms = 0.05;     ///< belt speed jitter per slot, fraction of the mean speed
  double speed_change = 0.05;   ///< end / start speed drawn from 1 +- this (uniform)
  double encoder_error = 0.02;  ///< the encoder's blur drawn from the true one x (1 +- this)
};

/// \brief The session a line runs: its config (code, slot time, light, camera,
/// processing) and the frame rate its camera runs at (0: unknown, as offline:
/// every window the cascade wants).
struct LinePath {
  session::SessionConfig config;
  double fps = 0;
};

/// \brief One label's frame: whether its content was among the codes read, and
/// what the session's stages took on it (convert, deblur, decode, second pass), ms.
struct LabelRead {
  bool read = false;
  double frame_ms = 0;
};

/// \brief Labels of one symbol at one module size.
class LabelLine {
 public:
  /// \brief Renders `contents` labels (random content of the symbology) of
  /// `kind` with modules of `module_px` pixels; `seed` draws the contents.
  /// Fails (message) when a label cannot be rendered.
  static LabelLine make(sim::SceneKind kind, double module_px, int contents, std::uint64_t seed);

  /// \brief Label number `label` passing under `path`'s line at a belt motion of
  /// `blur_px` per exposure along +x.
  LabelRead read(const LinePath& path, double blur_px, const LineMotion& motion,
                 std::uint64_t label) const;

  /// \brief The frame width (px) a label needs at a blur of `blur_px`.
  int frame_width(double blur_px) const;

  const std::string& error() const { return error_; }

 private:
  struct Label {
    std::string content;
    imaging::Plane fine;  ///< sim::kSimSupersample times finer than the camera
  };
  sim::SceneKind kind_ = sim::SceneKind::kCode128;
  std::vector<Label> labels_;
  std::uint64_t seed_ = 0;
  std::string error_;
};

/// \brief Slot boundaries (px) of one exposure of `blur_px` with a speed that
/// changes at a constant rate to `speed_ratio` (end / start) and per-slot jitter
/// of `jitter_rms` (rescaled so the slots add up to `blur_px`).
std::vector<double> line_slot_boundaries(int slots, double blur_px, double speed_ratio,
                                         double jitter_rms, std::uint64_t seed);

}  // namespace flutterscan::bench
