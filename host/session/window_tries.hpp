#pragma once
// The second pass's tries on one window (second_pass_tries.hpp names them),
// each a unit: it deblurs the window again its own way, pastes its latent into
// the frame's, reads the window (SecondPassWindow) and returns the values it
// read. run_second_pass decides which run, in what order, and pays for them.

#include <optional>
#include <string>
#include <vector>

#include "imaging/bar_sums.hpp"
#include "imaging/image.hpp"
#include "session/second_pass.hpp"
#include "session/second_pass_window.hpp"

namespace flutterscan::session {

/// \brief "tv": the window deblurred by tv (the reading weight, one thread),
/// pasted and read for every symbology. Its latent of the crop, or nullopt
/// where the deblur failed (the latents are then as they were). Its cost is
/// the window's (SecondPassBudget::estimate_ms of its pixels).
std::optional<imaging::Plane> tv_try(SecondPassWindow& window);

/// \brief A window's rows summed along its bars at one count of rows, and what
/// the sums' tries read them on: the try bar-sums makes them, tv-on-sums and
/// fit read them again their own ways.
struct BarSums {
  int half_rows = 0;         ///< 2 half_rows + 1 rows summed
  imaging::BarSlope slope;   ///< in the crop's coordinates
  std::vector<bool> across;  ///< the crop's rows whose sums all cross the bars
  imaging::Plane wiener;     ///< joint Wiener's latent of the sums (the crop's)
  imaging::Plane composite;  ///< the sums where all their rows cross the bars, tv's elsewhere
  double turn_rad = 0;       ///< the bars' lean from upright in the camera (0: read upright only)
};

/// \brief "bar-sums": the window's rows summed along its bars (17 rows, then 49
/// where that reads nothing), deblurred by joint Wiener and read for the
/// linear symbologies `linear`, upright and, where the bars lean, turned
/// upright. The frame keeps `tv` (tv's latent) except over the rows of the codes
/// the sums read. `record` gets the slope, the rows summed and the values read.
/// Returns the sums made, in order (the last read, if any did). Its cost is
/// part of the window's.
std::vector<BarSums> bar_sums_try(SecondPassWindow& window, const imaging::Plane& tv,
                                  const std::string& linear, BarSumsTry& record);

/// \brief The codes of `found` (read on tv's latent of a window's bar sums)
/// whose bars `sums` (the frame's latent with joint Wiener's sums where tv's
/// were: the light's evidence without tv's prior) support: judged by
/// reader::fit_bar_pattern, every character fitting at least 1 noise variance
/// better than any other allowed in its place. Formats it cannot judge are
/// not supported. Each code's verdict is added to `checked`.
std::vector<reader::DecodedCode> supported_reads(const imaging::Plane& sums,
                                                 std::vector<reader::DecodedCode> found,
                                                 std::vector<BarSumsTry::Checked>& checked);

/// \brief "tv-on-sums": `sums`' rows deblurred by tv at kBarSumsTvWeight and
/// read for `linear`; each value kept only where joint Wiener's sums support it
/// (supported_reads()). Adds to `record` (tv_rows, tv_checked, read). Costs
/// about as much as tv_try().
std::vector<std::string> tv_on_sums_try(SecondPassWindow& window, const BarSums& sums,
                                        const imaging::Plane& tv, const std::string& linear,
                                        BarSumsTry& record);

/// \brief What fit_try() is expected to cost on `window`, ms (two rows fitted).
double fit_estimate_ms(const SecondPassWindow& window);

/// \brief "fit": an EAN-13 read on joint Wiener's `sums` by fitting the symbol
/// itself (reader::read_ean13_by_fit), on two rows of the longest run of rows
/// across the bars that sum no row in common: both must read it. Reported as a
/// UPC-A where it starts with 0 and `upc_a` is read. Adds to `record` (fitted, read).
std::vector<std::string> fit_try(SecondPassWindow& window, const BarSums& sums,
                                 const imaging::Plane& tv, bool upc_a, BarSumsTry& record);

/// \brief "isotropic-tv": the window deblurred by tv with `weight` across the
/// motion as along it, read for every symbology; its latent stays where it
/// reads, else `tv` is put back. Adds to `record`. Costs about as much as tv_try().
std::vector<std::string> isotropic_tv_try(SecondPassWindow& window, double weight,
                                          const imaging::Plane& tv, IsotropicTry& record);

}  // namespace flutterscan::session
