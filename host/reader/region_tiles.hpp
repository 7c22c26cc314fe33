#pragma once
// Regions cut to what one frame's decode can afford. ZXing cannot be stopped
// inside a window, so a window's first view is the smallest unit of decode
// time: on a carton printed all over, the print is one region the size of the
// frame, and its first view alone costs more than the frame's share. Cut into
// tiles no larger than the decode budget reads in one view, overlapping by
// half a tile each way (a code up to half a tile in each direction lies whole
// in one of them), the region is read a tile or a few a frame: the tiles a
// frame leaves, later frames read first (a label passes through several).

#include <span>
#include <string>
#include <vector>

#include "reader/barcode_reader.hpp"

namespace flutterscan::reader {

/// \brief A tile of a region, and the region it was cut from.
struct RegionTile {
  LabelRegion tile;
  std::size_t region = 0;  ///< its index in the regions given
};

/// \brief The smallest tile's side, px: half of it (what the overlap keeps
/// whole) holds an EAN-13 and its quiet zones (113 modules) at 2.8 px a module.
/// Along the motion a label moves between frames, so a longer one is whole in
/// a tile of a later frame; across it, a code stays on its rows.
inline constexpr int kMinTileSide = 640;

/// \brief A tile's views look for linear codes on every 8th row and column
/// (DecodeWindow::linear_row_step): a linear symbol's bars are at least 25
/// modules tall (6.35 mm at 0.254-mm modules, the least height the Code 128
/// and Code 39 specifications recommend), 70 px at kMinTileSide's 2.8 px a
/// module, so 8 of its rows are looked at, 4 times the two agreeing rows ZXing
/// asks for. It cuts a view of print to about a third of ZXing's thorough
/// scan (every other row), which linear codes dominate.
inline constexpr int kTileRowStep = 8;

/// \brief What one view of a window full of print costs a megapixel, ms, on
/// this machine with `symbologies` and `try_rotate`: ZXing's first view of a
/// 640 x 640 window of random 4 px cells (print with edges everywhere, which no
/// symbology reads), timed once: ZXing's thorough scan (a tile's view costs less). What a session
/// starts from, before its frames say.
double view_cost_ms_per_mpx(const std::string& symbologies, bool try_rotate);

/// \brief `regions` (motion frame, `lines` across) with each larger than
/// `max_px` cut into square tiles of side max(kMinTileSide, sqrt(max_px)),
/// clipped to the region, every half side along and across (the last flush
/// with the region's end), each marked `tile`; `cut` kept on the tiles that touch the edge the
/// region is cut at (its first or last column). Regions within `max_px`, and all
/// of them where `max_px` <= 0, pass whole. A region whose rows were not
/// measured spans [0, lines).
std::vector<RegionTile> cut_to_tiles(std::span<const LabelRegion> regions, int lines,
                                     long long max_px);

}  // namespace flutterscan::reader
