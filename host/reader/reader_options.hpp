#pragma once
// The reader's options as one bundle: what every caller reads codes with (the
// session's workers, `flutterscan deblur --decode`, the accuracy sweep, the
// stability study and the session bench). The defaults are the session's
// (processing.symbologies, try_rotate, decode_area); a caller that wants
// otherwise says so, as the benches and `deblur --decode` do by reading the
// whole frame (whole_frame_options()).

#include <string>

#include "reader/barcode_reader.hpp"

namespace flutterscan::reader {

/// \brief How codes are read on a fused latent.
struct ReaderOptions {
  /// ZXing format names, comma-separated (check_symbologies()); fewer is faster.
  std::string symbologies = kDefaultSymbologies;
  /// Also look for 1-D codes turned by 90 degrees (about twice the decode time).
  bool try_rotate = true;
  /// The label paper only (windows around the paper runs) or the whole frame.
  DecodeArea area = DecodeArea::kLabels;
  /// The luminance views a window of paper or print cut by the frame's edge is
  /// read in (area "labels"): all of them, or fewer where the label is seen
  /// whole in another frame (the session's line: the linear view only).
  int cut_window_views = kLuminanceViews;
  /// A window ZXing reads nothing in is read by zbar too (zbar_reader.hpp: a
  /// quarter again of the five views' time on a window of noise). The
  /// session's cascade leaves it to its second pass, which reads those windows
  /// again under the frame's budget.
  bool second_decoder = true;
  /// Area "labels": the decode's time: windows are read in the order the
  /// regions are given, each view only while the decode has run less (the first
  /// window's first view always is) and where it is expected to end by the
  /// deadline; those not started and those cut short with nothing read are
  /// listed (BarcodeReadout::windows_left, windows_cut). budget.ms 0: every
  /// window in every view.
  DecodeBudget budget;
};

/// \brief The default options, reading the whole frame: what the benches and
/// `deblur --decode` (unless `--decode-area labels`) read with.
inline ReaderOptions whole_frame_options() {
  ReaderOptions options;
  options.area = DecodeArea::kFrame;
  return options;
}

}  // namespace flutterscan::reader
