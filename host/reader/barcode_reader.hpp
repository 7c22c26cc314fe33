#pragma once
// The barcode reader (ZXing-C++): every figure and every line reads codes
// here, with the same options unless the caller says otherwise: the session's
// workers, `flutterscan deblur --decode`, the accuracy sweep and the
// stability study. It finds codes on a fused latent image, with where they
// are, and the label regions (bright paper on the darker belt) whether a code
// was read on them or not: a region without a decode is what becomes a NO-READ.
// The options: the symbologies (kDefaultSymbologies), try-rotate (on) and the
// windows to look in (none: the whole image). Callers read with the bundle of
// reader_options.hpp through read_codes() (code_reading.hpp), which makes the
// windows from the label paper when the decode area is "labels".

#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "imaging/capture_model.hpp"
#include "imaging/image.hpp"
#include "reader/code_measure.hpp"

namespace flutterscan::reader {

/// \brief How a latent's reflectance reaches the decoder as 8-bit luminance:
/// linear (first); sRGB-encoded (a window the linear view reads nothing in:
/// dark or low-contrast print, as a camera's own encoding shows it);
/// sRGB-encoded from the window's black level (a window neither reads: ink
/// that is not black, as a camera that sets its black level shows it); and,
/// for linear codes only, sRGB-encoded from the black level to the paper
/// beside each pixel (a window none of those reads: a label darker than what
/// lies beside it on its rows, which ZXing's per-row threshold for linear
/// codes takes for the white); and, for matrix codes only, smoothed over a
/// module's centre and sRGB-encoded from the black level (a window none of
/// those reads: ZXing samples each module at one pixel, and a deblurred
/// latent's noise is the pixel's own).
enum class LuminanceView { kLinear, kSrgb, kSrgbFromBlack, kSrgbToPaper, kSmoothedFromBlack };
/// The luminance views, in the order a window is read in them.
inline constexpr int kLuminanceViews = 5;

/// \brief The linear (1-D) symbologies among `symbologies` (ZXing's names, as
/// processing.symbologies gives them); empty if it names none.
std::string linear_symbologies(const std::string& symbologies);

/// \brief Whether `symbologies` (ZXing's names, comma-separated, as
/// check_symbologies() passes them) names `format`, as ZXing parses both
/// ("EAN-13", "EAN13" and "ean13" are one).
bool names_symbology(const std::string& symbologies, const std::string& format);

/// \brief The view's name in logs: "linear", "srgb", "srgb-from-black", "srgb-to-paper",
/// "smoothed-from-black".
std::string luminance_view_name(LuminanceView view);

/// \brief One decoded barcode.
struct DecodedCode {
  std::string text;
  std::string format;  ///< ZXing's name: "Code128", "EAN-13", "QRCode", "DataMatrix", ...
  /// The ISO/IEC 15424 symbology identifier ZXing gives: "]C0" (Code 128), "]E0" (EAN-13),
  /// "]Q1" (QR model 2), "]d1" (Data Matrix ECC 200), ...
  std::string symbology_id;
  std::string ec_level;     ///< matrix codes: the error-correction level ZXing reports, if any
  int orientation_deg = 0;  ///< ZXing's: the symbol's reading direction, degrees
  double centre_x = 0;      ///< pixel column of the symbol's centre
  double centre_y = 0;
  double min_x = 0, max_x = 0;                       ///< extent along x
  LuminanceView luminance = LuminanceView::kLinear;  ///< the view it was read on
  /// The decoder that read it: "zxing", "zbar" (a linear code ZXing read in
  /// no view of its window: zbar_reader.hpp), or "fit" (an EAN-13 the session's
  /// second pass read on a window's bar sums by fitting the symbol itself:
  /// bar_pattern_fit.hpp).
  std::string decoder = "zxing";
  /// The latent it was read on: "first" (the frame's first pass), or the
  /// cascade's second-pass try that made it (session/second_pass_tries.hpp:
  /// "tv", "bar-sums", "tv-on-sums", "fit", "isotropic-tv").
  std::string pass = "first";
  /// What backs the value (read_evidence.hpp): "check" (its symbology's own
  /// check is strong), "halves" (an EAN or UPC read alike on both
  /// halves of its bars, each on its own; for an EAN-13 read by fit, two rows
  /// of its bar sums that share no row), or "decoders" (read alike by ZXing and zbar).
  std::string evidence;
  /// Where it lies (corners refined on the image for linear codes), its module
  /// size and its indicative print quality (measure_code()).
  CodeQuality quality;
};

/// \brief The symbologies read unless `processing.symbologies` names others.
/// Left out: Micro QR, whose sampler in Debian's ZXing 1.4 fails an assertion
/// on some deblurred frames (see assertion_guard.hpp); PDF417, whose error
/// correction in ZXing 1.4 has spun for more than 20 minutes on a noisy
/// deblurred frame (twice, docs/benchmarks.md: a worker would stop that long),
/// so a line reads it only where it names it; and DataBar, which conveyor
/// labels rarely carry. ZXing's names, comma-separated.
inline constexpr const char* kDefaultSymbologies =
    "Aztec,Codabar,Code39,Code93,Code128,DataMatrix,EAN-8,EAN-13,ITF,QRCode,UPC-A,UPC-E";

/// \brief "" if `symbologies` is a list of ZXing format names ZXing knows
/// (comma-separated, e.g. "Code128,QRCode"), else what is wrong with it.
std::string check_symbologies(const std::string& symbologies);

/// \brief The time a decode may take and what it expects a view to cost.
struct DecodeBudget {
  /// ms: a view is started while the decode has run less; 0: every window in every view.
  double ms = 0;
  /// ms; no view, the first window's included, is started that is expected to
  /// end later than this (at view_ms_per_mpx); < 0: none.
  double deadline_ms = -1;
  /// What one view of a window costs a megapixel, ms (0: unknown).
  double view_ms_per_mpx = 0;
};

/// \brief What one decode found.
struct BarcodeReadout {
  std::vector<DecodedCode> codes;
  /// Windows not decoded because three quarters of them lie in an earlier window that read a code.
  std::size_t windows_skipped = 0;
  /// The windows (their indices in the order given) the decode's time budget
  /// left: not started (windows_left), or cut short after their first view with
  /// nothing read (windows_cut).
  std::vector<std::size_t> windows_left;
  std::vector<std::size_t> windows_cut;
  /// The first views (the linear one, ZXing) of the windows ZXing scans
  /// thoroughly (linear_row_step 1): their time and their pixels, what one view
  /// of a window costs a pixel on this machine (a tile's costs less).
  double first_view_ms = 0;
  long long first_view_px = 0;
  /// Values of weak-check symbologies a decoder read that no second reading
  /// backed (read_evidence.hpp): not reported as reads, only logged.
  std::vector<DecodedCode> unconfirmed;
  /// Non-empty when the decoder failed an internal assertion on this image:
  /// its text. The codes read are then none (the frame is flagged, the session goes on).
  std::string decoder_fault;
};

/// \brief The texts of `readout`'s codes, in the order they were read.
std::vector<std::string> code_texts(const BarcodeReadout& readout);

/// \brief The rows `code`'s corners span: the least and the greatest y.
std::pair<double, double> corner_rows(const DecodedCode& code);

/// \brief Drops from `codes` each linear code read over one place as another
/// of its symbology family (read_evidence.hpp: EAN-13, EAN-8, UPC-A and UPC-E
/// are one) with another value (their boxes, widened by 4 px, meet and
/// share half the shorter one's length along the reading direction): one
/// symbol cannot be both, so one of them at least is a misread, and which is
/// not known. read_barcodes() does so with what it reads. Seen on real labels:
/// a Code 128 at 300 e- (code128-2-04, its rows summed along the bars),
/// 005993379497200536 on rows 164-201 over its value 005-3379497200006 on rows
/// 178-231; an EAN-13 at 3000 e- (ean13-2-07, tv's whole frame, 2 draws of 8),
/// 1790801816632 on rows 218-274 below its value 9780804816632 on rows 162-226;
/// each passing the check digit.
void drop_conflicting(std::vector<DecodedCode>& codes);

/// \brief Whether `a` and `b` are one symbol read twice (overlapping windows,
/// or a window read again): same text and format, and centres within 4 px or
/// each inside the other's corners (widened by 4 px): a linear code read on
/// two latents may be found over different rows of its bars.
bool same_symbol(const DecodedCode& a, const DecodedCode& b);

/// \brief `code` (its format known) measured on `latent` where a decoder
/// found it (`corners`), and its centre and extent along x from the corners
/// measured.
void measure_and_place(DecodedCode& code, const imaging::Plane& latent, const CodeCorners& corners);

/// \brief A rectangle of the latent image to decode: columns [x, x + width), rows [y, y + height),
/// read in at most its first `views` luminance views (LuminanceView's order)
/// and, where it reads nothing in all of them, by zbar if `second_decoder`.
struct DecodeWindow {
  int x = 0, y = 0, width = 0, height = 0;
  int views = kLuminanceViews;
  bool second_decoder = true;
  /// Rows of the latent this many apart or more share no sample of the frame,
  /// so the halves of a symbol split with that gap carry independent noise and
  /// may back its value (read_evidence.hpp): 1 where each row was deblurred on
  /// its own (joint Wiener), 2h + 1 on sums of 2h + 1 rows; 0 where a prior
  /// ties every row together (tv's), and only a second decoder backs a value.
  int independent_apart = 1;
  /// ZXing looks for linear codes on every `linear_row_step`-th row of the
  /// window (and, with try_rotate, column: turned codes) and for matrix codes
  /// on every pixel; 1: its thorough scan, every row or every other.
  int linear_row_step = 1;
};

/// \brief Every barcode of the named symbologies (check_symbologies() passed)
/// ZXing reads on `latent` (reflectance, clipped to 0..1), inside `windows`
/// (each decoded on its own, in at most its `views`; none: the whole image; drop_conflicting()),
/// each window on the linear view and, where that reads nothing, on the sRGB-encoded one, then on
/// the sRGB-encoded one from the window's black level, then (its linear
/// symbologies only) from the black level to the paper, then (its matrix
/// symbologies only) smoothed from the black level (LuminanceView); a window
/// ZXing reads nothing in is read once more by zbar (its linear symbologies,
/// from the black level: zbar_reader.hpp; its symbols with quiet_zones_clear()). A
/// linear symbol that reaches its window's edge along its reading direction is
/// cut by it and not taken for a read (it can decode to another value that
/// passes its check). A value of a weak-check symbology counts only where a
/// second reading backs it (read_evidence.hpp; else it goes to `unconfirmed`
/// and the window is read on in its next view). Positions are the latent's. `try_rotate`: also look
/// for 1-D codes turned by 90 degrees (about twice the decode time). `budget` (DecodeBudget): a
/// window is started, and read in a view after its first or by zbar, only while the decode has run
/// less than the budget (the first window's first view always is) and where the view is expected to
/// end by the budget's deadline; the windows it did not start and those it cut short with nothing
/// read are listed (windows_left, windows_cut).
BarcodeReadout read_barcodes(const imaging::Plane& latent,
                             const std::string& symbologies = kDefaultSymbologies,
                             bool try_rotate = true, std::span<const DecodeWindow> windows = {},
                             const DecodeBudget& budget = {});

/// \brief Modules beyond each end of a linear symbol that quiet_zones_clear()
/// judges: no more than any symbology's quiet zone (EAN-13 has 7 on its right,
/// Code 128 and Code 39 10). A symbol zbar finds inside another's bars, at
/// half their module, may sit beside one of that symbol's wide spaces (4 of its
/// modules, 8 of the false symbol's): judged over 4 modules, ean13-2-09's
/// misread passed.
inline constexpr double kQuietModules = 7;

/// \brief The same on the right of an EAN or UPC symbol, where its add-on (2
/// or 5 digits) may follow: 7-12 modules on, 4-6 past the end measured on a
/// real book's EAN-13 (ean13-2-04, whose read a 7-module check refused).
inline constexpr double kAddOnQuietModules = 4;

/// \brief Whether the linear `code` (measured on `latent`) has quiet zones:
/// on its centre line and the lines a quarter of its height either side, the
/// kQuietModules (kAddOnQuietModules) modules beyond each end from one and a half out (its last
/// edge's blur), averaged over the three lines and one module along them, are
/// nowhere as dark as a bar (a quarter of the way from its bars' reflectance
/// to its spaces'). Beyond the latent, or unmeasured: not judged (true).
/// read_barcodes() takes zbar's reads only where it holds: zbar takes a run of
/// another symbol's bars for a symbol of half their module where that passes
/// the check digit (on a real label's EAN-13 turned and read in the dark:
/// 9488244348880 for 9784872348880); the bars beside it are its tell.
bool quiet_zones_clear(const DecodedCode& code, const imaging::Plane& latent);

/// \brief The codes in `window` of `latent` read with the window turned upright
/// by `turn_rad`: resampled (bilinear; the latent around the window fills the
/// turned plane's corners, its edge beyond the latent) so that a
/// line at `turn_rad` from the vertical (positive: its lower end toward larger
/// x) stands vertical. A linear code whose bars lean so that no row crosses the
/// whole symbol (a short code turned 10 degrees) is read so. Positions (centre,
/// extent, corners) are mapped back to the latent's.
BarcodeReadout read_barcodes_turned(const imaging::Plane& latent, const DecodeWindow& window,
                                    double turn_rad, const std::string& symbologies,
                                    bool try_rotate);

/// \brief A run of columns [begin, end) where the image is mostly label paper,
/// and the rows [across_begin, across_end) that hold its paper.
struct LabelRegion {
  int begin = 0;
  int end = 0;
  /// Touches the first or last column, or reaches it through a dark gap of at most max_gap or
  /// through bars with paper above and below them: the label may go on outside the frame.
  bool cut = false;
  /// Rows of the paper across the motion; both 0: not measured (every row).
  int across_begin = 0;
  int across_end = 0;
  /// A tile of a larger region, cut to what the decode's budget reads
  /// (region_tiles.hpp): read with kTileRowStep.
  bool tile = false;

  /// \brief Whether the rows were measured (if not, the region spans every row).
  bool rows_measured() const { return across_end > across_begin; }
  /// \brief Whether `other` lies within this region's columns and (measured) rows.
  bool contains(const LabelRegion& other) const {
    return other.begin >= begin && other.end <= end &&
           (!rows_measured() ||
            (other.across_begin >= across_begin && other.across_end <= across_end));
  }
  /// \brief Whether `other` shares columns and (measured) rows with this region.
  bool overlaps(const LabelRegion& other) const {
    return other.begin < end && other.end > begin &&
           (!rows_measured() ||
            (other.across_begin < across_end && other.across_end > across_begin));
  }
};

/// \brief Paper along x: columns where at least `min_fraction` of the pixels
/// are brighter than `paper_threshold`, in runs at least `min_width` wide
/// (narrower ones only where the frame's edge cuts them). Dark gaps up to
/// `max_gap` columns (the bars of a linear code) do not split a run. Across
/// the motion each run spans the rows from the first to the last where at
/// least `min_fraction` of the run's columns are paper (the motion frame's
/// rows are the camera's across coordinate, whatever the direction). Runs
/// in rows they share are one run when every column of the gap between them
/// has paper in `min_fraction` of their rows (at least 2 pixels): the margins
/// above and below a code's bars, which a belt between labels does not have.
std::vector<LabelRegion> find_paper_runs(const imaging::Plane& latent,
                                         double paper_threshold = 0.62, double min_fraction = 0.05,
                                         int min_width = 48, int max_gap = 16);

/// \brief Where the session looks for codes: the whole frame, or the label
/// paper only (decode_windows()), which is faster and finds the same codes on
/// labels brighter than the belt.
enum class DecodeArea { kFrame, kLabels };

/// \brief "frame", "labels".
std::string decode_area_name(DecodeArea area);
/// \brief The decode area called `name` (see decode_area_name), if any.
std::optional<DecodeArea> decode_area_from_name(const std::string& name);

/// \brief Windows of a `width` x `height` latent around `runs` (found along
/// the motion: x for +-x, y for +-y, in the motion frame of `direction`), each
/// widened by `margin` px along the motion and across it (a run whose rows
/// were not measured spans the frame across).
std::vector<DecodeWindow> decode_windows(std::span<const LabelRegion> runs, int width, int height,
                                         imaging::Direction direction, int margin = 24);

}  // namespace flutterscan::reader
