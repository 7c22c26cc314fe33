#include "reader/code_reading.hpp"

#include "reader/region_tiles.hpp"

#include <vector>

namespace flutterscan::reader {

CodeReading read_codes(const imaging::Plane& latent, std::span<const LabelRegion> paper,
                       imaging::Direction direction, const ReaderOptions& options) {
  CodeReading out;
  if (options.area == DecodeArea::kFrame) {
    DecodeWindow whole{0, 0, latent.width, latent.height};
    whole.second_decoder = options.second_decoder;
    out.readout = read_barcodes(latent, options.symbologies, options.try_rotate, {&whole, 1});
    return out;
  }
  std::vector<DecodeWindow> windows = decode_windows(paper, latent.width, latent.height, direction);
  for (std::size_t i = 0; i < windows.size(); ++i) {
    if (paper[i].cut) windows[i].views = options.cut_window_views;
    windows[i].second_decoder = options.second_decoder;
    if (paper[i].tile) windows[i].linear_row_step = kTileRowStep;
  }
  out.windows = windows.size();
  if (!windows.empty())
    out.readout =
        read_barcodes(latent, options.symbologies, options.try_rotate, windows, options.budget);
  return out;
}

}  // namespace flutterscan::reader
