#include "reader/region_tiles.hpp"

#include <algorithm>
#include <cmath>
#include <random>

namespace flutterscan::reader {
namespace {

/// Tile starts over [begin, end) for tiles of `side`: every half side, the last flush with end.
std::vector<int> tile_starts(int begin, int end, int side) {
  if (end - begin <= side) return {begin};
  std::vector<int> starts;
  for (int s = begin; s + side < end; s += side / 2) starts.push_back(s);
  starts.push_back(end - side);
  return starts;
}

}  // namespace

double view_cost_ms_per_mpx(const std::string& symbologies, bool try_rotate) {
  constexpr int kSide = 640, kCell = 4;
  imaging::Plane print(kSide, kSide);
  std::mt19937 rng(1);
  std::bernoulli_distribution dark(0.5);
  for (int cy = 0; cy < kSide; cy += kCell)
    for (int cx = 0; cx < kSide; cx += kCell) {
      const float v = dark(rng) ? 0.1f : 0.9f;
      for (int y = cy; y < cy + kCell; ++y)
        for (int x = cx; x < cx + kCell; ++x) print.at(x, y) = v;
    }
  DecodeWindow window{0, 0, kSide, kSide};
  window.views = 1;
  window.second_decoder = false;
  const BarcodeReadout readout = read_barcodes(print, symbologies, try_rotate, {&window, 1});
  return readout.first_view_ms / (static_cast<double>(readout.first_view_px) / 1e6);
}

std::vector<RegionTile> cut_to_tiles(std::span<const LabelRegion> regions, int lines,
                                     long long max_px) {
  std::vector<RegionTile> out;
  const int side =
      max_px > 0 ? std::max(kMinTileSide, static_cast<int>(std::sqrt(static_cast<double>(max_px))))
                 : 0;
  for (std::size_t i = 0; i < regions.size(); ++i) {
    const LabelRegion& r = regions[i];
    const int top = r.rows_measured() ? r.across_begin : 0;
    const int bottom = r.rows_measured() ? r.across_end : lines;
    const long long px = static_cast<long long>(r.end - r.begin) * (bottom - top);
    if (max_px <= 0 || px <= max_px) {
      out.push_back({r, i});
      continue;
    }
    for (const int across : tile_starts(top, bottom, side))
      for (const int along : tile_starts(r.begin, r.end, side)) {
        LabelRegion tile;
        tile.begin = along;
        tile.end = std::min(r.end, along + side);
        tile.across_begin = across;
        tile.across_end = std::min(bottom, across + side);
        tile.cut = r.cut && (tile.begin == r.begin || tile.end == r.end);
        tile.tile = true;
        out.push_back({tile, i});
      }
  }
  return out;
}

}  // namespace flutterscan::reader
