#pragma once
// A categorical heat map rendered to PNG with Cairo: a grid of cells, each
// coloured by a category (e.g. the winning capture scheme) and labelled with
// a short text (e.g. its margin in dB), with a legend of the categories.

#include <string>
#include <vector>

namespace flutterscan::plot {

struct HeatMap {
  std::string title, x_label, y_label;
  std::vector<std::string> columns;     ///< x tick labels, left to right
  std::vector<std::string> rows;        ///< y tick labels, bottom to top
  std::vector<std::string> categories;  ///< legend entries; colours follow this order
  std::vector<int> category;  ///< rows x columns, row-major from the bottom row; -1 = empty
  std::vector<std::string> cell_text;  ///< rows x columns, same order; may be empty
  std::vector<std::string> notes;      ///< small lines under the title
};

/// \brief Renders `map` and writes it atomically as a PNG; "" on success, else
/// a message naming `path` and what failed (sizes that disagree, a missing folder).
std::string write_png(const HeatMap& map, const std::string& path, int width = 1200,
                      int height = 720);

}  // namespace flutterscan::plot
