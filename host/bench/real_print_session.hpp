#pragma once
// The session's default per-frame path (session::process_frame: the model
// fit, the deblur, the paper found, the decode, the cascade's second pass) on
// frames made outside a session: a line with the session's default config at
// one light level, its encoder reporting a given blur along +x, offline (every
// second pass the cascade wants runs, as `flutterscan replay` runs them).

#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include "imaging/capture_model.hpp"

#include "imaging/image.hpp"
#include "reader/barcode_reader.hpp"
#include "session/second_pass.hpp"
#include "session/session_config.hpp"

namespace flutterscan::bench {

/// \brief What the session reads on one frame.
struct SessionRead {
  /// Its codes, each as its sighting reports it (value, format, decoder, pass),
  /// and the values it logged as unconfirmed (value, format, decoder, pass).
  reader::BarcodeReadout readout;
  nlohmann::json log;  ///< the frame's line of session.jsonl (times_ms: its stages)

  /// \brief The windows it decoded, from its log: the first pass's (decode_windows;
  /// 1, the whole frame, where it has none) and the second pass's; none where the
  /// session stopped on the frame (its log's error).
  int windows() const;
};

/// \brief The second-pass credit a line's `workers` leave each frame at `fps` frames a
/// second (session::SecondPassBudget: period x workers x its share; the first pass's
/// own time not taken off: the most a frame gets in a steady run), ms.
inline double line_credit_ms(double fps, int workers) {
  return 1000.0 / fps * workers * session::SecondPassBudget::kShare;
}

/// \brief The session's default config for a line at light level `electrons`
/// (optics.electrons, given), one row thread per worker, codes looked for in
/// `area`, the second pass's `tries` with a credit of `second_pass_ms` per
/// frame (session::kMaxSecondPassMs: offline, every window) and the first
/// pass's decode time `decode_ms` (processing.decode_ms; "auto", -1: every
/// window while the frame rate is unknown). Not checked: SessionLine checks it.
session::SessionConfig line_config(double electrons,
                                   reader::DecodeArea area = reader::ReaderOptions{}.area,
                                   const session::SecondPassTries& tries = {},
                                   double second_pass_ms = session::kMaxSecondPassMs,
                                   double decode_ms = -1);

class SessionLine {
 public:
  /// \brief Frames of `width` x `height` (RGB, the config's bit depth) moving
  /// `blur_px` along +x per exposure, read as a session with `config` reads them
  /// (its code, light, camera and processing). Throws if the config does not
  /// check.
  SessionLine(session::SessionConfig config, int width, int height, double blur_px);
  /// \brief Frames of `width` x `height` (RGB, 12 bits) moving `blur_px` along +x
  /// per exposure at light level `electrons`, codes looked for in `area` (the
  /// session's default: the label paper). Throws if the config does not check.
  SessionLine(int width, int height, double blur_px, double electrons,
              reader::DecodeArea area = reader::ReaderOptions{}.area);
  /// \brief The same with the second pass's `tries`, a credit of
  /// `second_pass_ms` per frame (session::kMaxSecondPassMs: offline, every
  /// window) and the first pass's decode time `decode_ms` (processing.decode_ms;
  /// "auto", -1: every window, the frame rate being unknown offline).
  SessionLine(int width, int height, double blur_px, double electrons, reader::DecodeArea area,
              const session::SecondPassTries& tries, double second_pass_ms, double decode_ms = -1);

  /// \brief The capture model the session builds for each of these frames:
  /// what a simulated frame must be recorded with.
  const imaging::CaptureModel& model() const { return model_; }

  /// \brief Frames come at `fps` to `workers` workers, each arriving as read()
  /// starts: the decode's and the second pass's "auto" budgets and the frame's
  /// deadline follow the session's rules for that line (by default the frame
  /// rate is unknown, as offline).
  void at_frame_rate(double fps, int workers);

  /// \brief What the session reads on `dn` (a frame recorded with model()).
  SessionRead read(const imaging::Image& dn) const;

 private:
  session::SessionConfig config_;
  int width_;
  int height_;
  int encoder_counts_;
  imaging::CaptureModel model_;
  double fps_ = 0;  ///< 0: the frame rate unknown
};

}  // namespace flutterscan::bench
