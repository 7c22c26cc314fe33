#pragma once
// The cascade's second pass (processing.method = "cascade", the session's
// default; docs/session.md, "The cascade"). Joint Wiener deblurs the whole
// frame; each judged label window, and each code region off the labels, where
// it read nothing is deblurred again, alone, by tv (slower, and reads far more in dim light),
// pasted into the fused frame and read again (and, for a linear code tv does not read, its rows
// summed along the bars: imaging/bar_sums.hpp), while the session's CPU budget lasts. A window the
// budget cannot pay for is counted and flagged, never dropped silently.

#include <array>
#include <cstdint>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "imaging/capture_model.hpp"
#include "imaging/image.hpp"
#include "imaging/motion_frame.hpp"
#include "imaging/total_variation.hpp"
#include "reader/barcode_reader.hpp"
#include "reader/reader_options.hpp"
#include "session/second_pass_tries.hpp"

namespace flutterscan::session {

/// \brief The CPU the workers may spend on second passes, shared by them: a
/// credit of milliseconds that each frame tops up by its share of the line's
/// frame period (period x workers x kShare, less the frame's first pass) and
/// each window spends. Bounded both ways (a burst of NO-READs spends at most
/// two frame periods of every worker; a slow stretch owes at most as much).
class SecondPassBudget {
 public:
  /// The share of the workers' time the session lets itself use (headroom for the rest).
  static constexpr double kShare = 0.85;

  /// \brief `per_frame_ms` < 0: from the frame rate (the cameras' timestamps)
  /// and `workers`; >= 0: that many ms of credit per frame, whatever the rate.
  SecondPassBudget(double per_frame_ms, int workers);

  /// \brief The frame period the camera was set to, ms: the frame's share
  /// until the cameras' timestamps show the period (the first two frames a
  /// worker finishes), which then replaces it.
  void expect_period_ms(double period_ms);
  /// \brief Frame `index`, exposed at camera time `camera_ns`, whose first pass
  /// took `first_pass_ms` (wall time on its worker): its credit is added.
  void add_frame(std::uint64_t index, std::int64_t camera_ns, double first_pass_ms);
  /// \brief Spends `estimate_ms` if the credit holds it (true), else nothing (false).
  bool take(double estimate_ms);
  /// \brief A window that was estimated at `estimate_ms` took `actual_ms`:
  /// the credit and the cost model follow what it really took.
  void settle(double estimate_ms, double actual_ms, std::size_t pixels);
  /// \brief What a window of `pixels` pixels is expected to cost, ms.
  double estimate_ms(std::size_t pixels) const;
  /// \brief The credit left, ms.
  double credit_ms() const;
  /// \brief The frame period the cameras' timestamps show (until then the one
  /// expected), ms; 0: not known yet.
  double period_ms() const;
  /// \brief The workers' time a frame has, all workers together: the frame period
  /// the cameras' timestamps show (until then the one expected) times the
  /// workers times kShare, ms (0: the period is not known yet).
  double frame_share_ms() const;

 private:
  mutable std::mutex mutex_;
  double per_frame_ms_;
  int workers_;
  double credit_ms_ = 0;
  double period_ms_ = 0;          ///< the frame period the timestamps show (0: not yet known)
  bool period_measured_ = false;  ///< period_ms_ from the timestamps, not expect_period_ms()
  std::uint64_t last_index_ = 0;
  std::int64_t last_camera_ns_ = 0;
  bool seen_frame_ = false;
  double ms_per_megapixel_ = 80;  ///< tv-40 on one thread, updated by every window
  /// frame_share_ms() with the mutex held.
  double share_locked() const { return period_ms_ * workers_ * kShare; }
};

/// \brief Where something lies on the belt: [begin, end) along the motion in
/// belt px (position along the motion less the belt's travel) and [across_begin,
/// across_end) across it (the motion frame's lines; both 0: every line).
struct BeltBox {
  double begin = 0, end = 0;
  double across_begin = 0, across_end = 0;
};

/// \brief The box `code` (read on a latent `width` x `height` in the camera's
/// orientation) covers on the belt at `travel_px`: its corners' extent.
BeltBox belt_box(const reader::DecodedCode& code, imaging::Direction direction, int width,
                 int height, double travel_px);

/// \brief Boxes on the belt seen lately, shared by the workers: where codes were
/// read (a window whose object was read in another frame needs no second pass,
/// so the budget goes to the objects not read yet) or where the first pass
/// decoded windows (under its budget the regions not tried yet go first).
/// Bounded: the last kKept boxes.
class BeltReads {
 public:
  static constexpr std::size_t kKept = 256;
  void add(const BeltBox& code);
  /// \brief Whether a code read covers part of `region` (along the motion, and
  /// across it where the region's lines are given): a code leaving the view
  /// whose centre has left already still counts.
  bool any_over(const BeltBox& region) const;

 private:
  mutable std::mutex mutex_;
  std::vector<BeltBox> reads_;  ///< a ring of kKept
  std::size_t next_ = 0;
};

/// \brief A window's rows summed along its bars and deblurred again
/// (imaging/bar_sums.hpp): tried where tv read no linear code.
struct BarSumsTry {
  double slope = 0;  ///< the bars' slope the last try summed along at the window's centre,
                     ///< px along the motion per row
  /// the slope's change across the window along its centre row, the last try's
  /// (bars in perspective: imaging::BarSlope); 0: parallel bars
  double slope_change = 0;
  std::vector<int> rows;          ///< the rows summed of each try made, in order
  std::vector<std::string> read;  ///< the codes the last try read
  /// tv on the sums, where joint Wiener's read nothing: the rows summed of each
  /// tv try made, and each value a tv try read, checked against joint Wiener's
  /// sums (reader::fit_bar_pattern).
  std::vector<int> tv_rows;
  struct Checked {
    std::string text;
    std::string format;
    double margin = 0;    ///< the worst character's margin, noise variances (0 if not judged)
    std::string problem;  ///< why it was not judged, or (the fit) why nothing was read
    /// The value counts: tv's, judged and every character held by 1 noise
    /// variance or more; the fit's, read alike on two rows of the sums that
    /// share no row, every character kMinFittedReadMargin clear.
    bool kept = false;
  };
  std::vector<Checked> tv_checked;
  /// Where neither read anything and EAN-13 is read: the sums' EAN-13 read by
  /// fit (reader::read_ean13_by_fit) at each try, kept or why not.
  std::vector<Checked> fitted;
};

/// \brief tv's kappa for the isotropic tries, in turn: the reading weight, then
/// half of it. The weight that reads bars best (imaging::kReadingWeightPerNoise)
/// flattens small modules: as in TV denoising, a feature loses contrast about
/// in proportion to the weight times its edge length over its area, and an
/// isotropic prior puts four edges round a module where the anisotropic one
/// counts a bar's two along the motion; half the weight treats a module of one
/// width as the reading weight treats a bar of that width.
inline constexpr std::array<double, 2> kIsotropicWeights = {imaging::kReadingWeightPerNoise,
                                                            imaging::kReadingWeightPerNoise / 2};

/// \brief A window deblurred again by tv with the same weight across the motion
/// as along it, at each of kIsotropicWeights in turn until one reads.
struct IsotropicTry {
  std::vector<double> weights;    ///< tv's kappa of each try made, in order
  std::vector<std::string> read;  ///< the codes the last try read
};

/// \brief One try's run in one window (window_tries.hpp), in the order they ran.
struct TryRun {
  std::string name;  ///< the try's (second_pass_tries.hpp), or "tv"
  /// What the budget was charged before it ran, ms; 0 for "bar-sums", which is
  /// charged with tv in the window's estimate (tv's estimate_ms).
  double estimate_ms = 0;
  double ms = 0;                  ///< what it took, wall time
  std::vector<std::string> read;  ///< the values it read
};

/// \brief One window the second pass deblurred again.
struct WindowRetry {
  reader::DecodeWindow window;    ///< in the frame (camera coordinates)
  double ms = 0;                  ///< its deblurs and decodes, wall time
  std::vector<std::string> read;  ///< the codes it read (tv's, the bar sums', the isotropic tv's)
  std::vector<TryRun> tries;      ///< each try that ran, in order
  std::optional<BarSumsTry> bar_sums;  ///< absent: not tried
  /// tv with an isotropic prior (the window again where nothing else
  /// read); absent: not tried.
  std::optional<IsotropicTry> isotropic;
};

/// \brief What a frame's second pass did.
struct SecondPass {
  std::vector<WindowRetry> retried;
  int skipped = 0;      ///< windows left as they were: the budget was spent
  int read_before = 0;  ///< windows left as they were: their object was read in another frame
  /// Windows and tries not started: they would end past the frame's deadline.
  int past_deadline = 0;
  /// The frame's line entry: {"windows": [...], "skipped": n, "read_before": n,
  /// "past_deadline": n (where any), "credit_ms": c}.
  nlohmann::json log(double credit_ms) const;
};

/// \brief Where the second pass works: the frame in electrons and its model
/// (the first pass's), and the fused latent in the motion frame and, unless
/// the motion is +x (then they are one plane), in the camera's orientation.
struct SecondPassFrame {
  const imaging::MotionFrame& electrons;
  const imaging::CaptureModel& model;
  imaging::Plane& motion_latent;
  imaging::Plane* camera_latent;  ///< null: the motion latent is the camera's
  double travel_px = 0;           ///< the belt's travel at this frame (belt = along - travel)
  /// When the frame's result is due, on the session's clock (session_clock.hpp), ns; 0: never.
  std::int64_t deadline_ns = 0;
};

/// \brief The paper runs of `paper` (the motion frame's) where `readout` has no
/// code (its centre outside the run's decode window): the windows the first
/// pass read nothing in.
std::vector<reader::LabelRegion> unread_runs(std::span<const reader::LabelRegion> paper,
                                             const reader::BarcodeReadout& readout,
                                             imaging::Direction direction, int width, int height);

/// \brief The regions to deblur again: each of `unread_paper` (the judged
/// labels), and each of `unread_code` (where the latent looks like a code,
/// reader::find_code_regions) that overlaps none of them (a code printed on
/// something other than white label paper).
std::vector<reader::LabelRegion> retry_regions(std::span<const reader::LabelRegion> unread_paper,
                                               std::span<const reader::LabelRegion> unread_code);

/// \brief Deblurs each of `unread` whose object `reads` has not seen read
/// again with tv (one thread), alone with the margin its blur needs, pastes it
/// into the latents, and reads its decode window again with `options`; where
/// that reads no linear code, and `options` reads linear symbologies, the
/// window's rows summed along its bars (17 rows, then 49 where that reads
/// nothing) are deblurred (joint Wiener), pasted and read for those (tv's
/// latent is put back if they read nothing). A window
/// where neither read anything, and nothing was read before, is deblurred again
/// by tv with an isotropic prior, at each of kIsotropicWeights while nothing
/// reads and `budget` holds another window, and read for every symbology (its
/// latent kept only where it reads). A window
/// whose codes of `readout` (read before it) tv's latent does not read again
/// keeps the latent it had. Only the `tries` switched on run beyond tv's. The
/// codes found, each with the try that read it (DecodedCode::pass), are added
/// to `readout` and to `reads`.
SecondPass run_second_pass(const SecondPassFrame& frame,
                           std::span<const reader::LabelRegion> unread,
                           const reader::ReaderOptions& options, const SecondPassTries& tries,
                           SecondPassBudget& budget, BeltReads& reads,
                           reader::BarcodeReadout& readout);

/// \brief The cascade on one frame outside a line (`flutterscan deblur --method
/// cascade`): `frame`'s latents (joint Wiener's) read with `options` (the
/// whole frame, or the paper runs and code regions found on the motion latent,
/// as options.area says), then every paper run and code region deblurred again
/// by tv and read (run_second_pass, no budget): the latents show tv's (or the
/// bar sums') over every window, joint Wiener's only where tv's would lose a
/// code it read, and `backdrop` (the frame's latent in the motion frame, made
/// otherwise: tv's on the whole frame) everywhere else, unless it is empty.
/// The codes of both passes (the second pass's `tries`); the second pass's log line in `log`.
reader::BarcodeReadout read_with_cascade(const SecondPassFrame& frame,
                                         const imaging::Plane& backdrop,
                                         const reader::ReaderOptions& options,
                                         const SecondPassTries& tries, nlohmann::json& log);

}  // namespace flutterscan::session
