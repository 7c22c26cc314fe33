#pragma once
// One window of the cascade's second pass (second_pass.hpp): the crop of the
// frame deblurred again around it, the latents its tries paste into, and the
// reading of the window on them. The tries (window_tries.hpp) work through it;
// the driver (run_second_pass) owns the budget, the order of the tries and the log.

#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "imaging/image.hpp"
#include "imaging/motion_frame.hpp"
#include "reader/barcode_reader.hpp"
#include "reader/code_regions.hpp"
#include "reader/reader_options.hpp"
#include "session/second_pass.hpp"

namespace flutterscan::session {

/// \brief Along and across the motion, what a window keeps around its paper
/// or code region: the decode window's margin (reader::decode_windows' default).
inline constexpr int kWindowMargin = 24;

/// \brief reader::DecodeWindow::independent_apart of a latent whose prior
/// ties its rows together (tv's): halves back no value read on it.
inline constexpr int kRowsTied = 0;

/// \brief Whether camera point (x, y) lies in `w`.
bool in_window(const reader::DecodeWindow& w, double x, double y);

class SecondPassWindow {
 public:
  /// \brief The window around paper run or code region `run` of `frame` (motion
  /// frame), read with `options`; what it reads joins `readout` and `reads`.
  /// Check usable() before anything else.
  SecondPassWindow(const SecondPassFrame& frame, const reader::LabelRegion& run,
                   const reader::ReaderOptions& options, reader::BarcodeReadout& readout,
                   BeltReads& reads);

  /// \brief Whether the window has a crop to deblur (a run too short for its
  /// blur, or at the frame's edge, has none).
  bool usable() const { return crop_.has_value(); }
  /// \brief The crop's samples (pixels), what tv's cost follows.
  std::size_t pixels() const;
  /// \brief The crop in electrons, in the motion frame (+x): columns
  /// crop_begin().. of the frame's lines first_line()...
  const imaging::MotionFrame& crop() const { return *crop_; }
  const imaging::CaptureModel& model() const { return frame_.model; }
  const reader::ReaderOptions& options() const { return options_; }
  imaging::Direction direction() const { return frame_.electrons.direction(); }
  const reader::DecodeWindow& window() const { return window_; }
  /// \brief The crop's columns kept in the latents ([keep_begin, keep_end) of
  /// the crop's, the decode window's margin about the run).
  int keep_begin() const { return keep0_ - c0_; }
  int keep_end() const { return keep1_ - c0_; }
  /// \brief The crop's first column and line in the motion frame, and the
  /// frame's columns (imaging::camera_point() maps the crop's points with them).
  int crop_begin() const { return c0_; }
  int first_line() const { return r0_; }
  int frame_along() const { return frame_.electrons.along(); }

  /// \brief The first pass's latent over the crop (the columns kept; the rest
  /// uninitialised), as it was before any try pasted.
  const imaging::Plane& first() const { return first_; }
  /// \brief The latent the frame reads in the camera's orientation.
  const imaging::Plane& camera() const;

  /// \brief Writes `latent` (the crop's) into the frame's latents over the
  /// columns kept or, given `codes`, over their rows only (their corners' rows
  /// widened by 4 px, whatever the column).
  void paste(const imaging::Plane& latent, std::span<const reader::DecodedCode> codes = {});
  /// \brief Reads the window on the latents as pasted, whose rows
  /// `independent_apart` or more apart share no sample of the frame
  /// (reader::DecodeWindow's: kRowsTied for tv's latents; 2h + 1 for joint
  /// Wiener's sums of 2h + 1 rows), upright or turned by `turn_rad`: the codes
  /// the readout does not hold yet. Values no second reading backs join the
  /// readout's unconfirmed.
  std::vector<reader::DecodedCode> read(int independent_apart, const std::string& symbologies,
                                        double turn_rad = 0);
  /// \brief `codes`, read on the latent try `pass` made, join the readout and
  /// the belt's reads. Returns their values.
  std::vector<std::string> take(std::vector<reader::DecodedCode> codes, const std::string& pass);
  /// \brief read() and take() (as try `pass`).
  std::vector<std::string> read_and_take(const std::string& pass, int independent_apart,
                                         const std::string& symbologies, double turn_rad = 0);

  /// \brief The codes read in the window before it was deblurred again (the
  /// first pass's, offline): a latent pasted must read them too, or it is not kept.
  const std::vector<reader::DecodedCode>& held() const { return held_; }
  /// \brief Whether the readout holds `code` already (reader::same_symbol).
  bool holds(const reader::DecodedCode& code) const;
  /// \brief Whether the last read() read every code of held().
  bool held_read() const { return held_read_; }
  /// \brief Whether a linear code lies in the window: held, or read by a try.
  bool linear_read() const;
  /// \brief The values the tries read, in order.
  const std::vector<std::string>& read_values() const { return read_values_; }

 private:
  const SecondPassFrame& frame_;
  const reader::ReaderOptions& options_;
  reader::BarcodeReadout& readout_;
  BeltReads& reads_;
  int keep0_ = 0, keep1_ = 0, c0_ = 0, c1_ = 0, r0_ = 0, r1_ = 0;
  reader::DecodeWindow window_;
  std::optional<imaging::MotionFrame> crop_;
  imaging::Plane first_;
  std::vector<reader::DecodedCode> held_;
  bool held_read_ = true;
  std::vector<std::string> read_values_;
  bool linear_taken_ = false;
};

}  // namespace flutterscan::session
