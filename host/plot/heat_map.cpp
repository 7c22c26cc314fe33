#include "plot/heat_map.hpp"

#include <cairo.h>

#include <algorithm>
#include <memory>

#include "plot/png_file.hpp"

namespace flutterscan::plot {
namespace {

struct Colour {
  double r, g, b;
};

/// Distinguishable fills, light enough for dark text on top.
constexpr Colour kPalette[] = {
    {0.55, 0.71, 0.90}, {0.98, 0.65, 0.45}, {0.60, 0.85, 0.60}, {0.93, 0.58, 0.62},
    {0.78, 0.68, 0.90}, {0.83, 0.73, 0.58}, {0.96, 0.80, 0.95}, {0.78, 0.78, 0.78},
    {0.86, 0.86, 0.50}, {0.55, 0.88, 0.90}, {0.99, 0.88, 0.55}, {0.70, 0.90, 0.80},
};

void text(cairo_t* cr, const std::string& s, double x, double y, double ax, double ay) {
  cairo_text_extents_t e;
  cairo_text_extents(cr, s.c_str(), &e);
  cairo_move_to(cr, x - ax * e.width - e.x_bearing, y - ay * e.height - e.y_bearing);
  cairo_show_text(cr, s.c_str());
}

void font(cairo_t* cr, double size, bool bold) {
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL,
                         bold ? CAIRO_FONT_WEIGHT_BOLD : CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, size);
}

void draw(cairo_t* cr, const HeatMap& map, int width, int height) {
  const double scale = std::min(width / 1200.0, height / 720.0);
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_paint(cr);
  cairo_set_source_rgb(cr, 0, 0, 0);
  font(cr, 24 * scale, true);
  text(cr, map.title, width / 2.0, 34 * scale, 0.5, 0.5);
  font(cr, 15 * scale, false);
  cairo_set_source_rgb(cr, 0.35, 0.35, 0.35);
  for (std::size_t i = 0; i < map.notes.size(); ++i)
    text(cr, map.notes[i], width / 2.0, (62 + 20 * static_cast<double>(i)) * scale, 0.5, 0.5);

  const double top = (80 + 20 * static_cast<double>(map.notes.size())) * scale;
  const double left = 110 * scale, right = width - 250 * scale, bottom = height - 80 * scale;
  const auto columns = static_cast<double>(map.columns.size());
  const auto rows = static_cast<double>(map.rows.size());
  const double cell_w = (right - left) / columns, cell_h = (bottom - top) / rows;
  font(cr, std::min(16.0 * scale, cell_h * 0.35), false);
  for (std::size_t r = 0; r < map.rows.size(); ++r)
    for (std::size_t c = 0; c < map.columns.size(); ++c) {
      const std::size_t i = r * map.columns.size() + c;
      const double x = left + cell_w * static_cast<double>(c);
      const double y = bottom - cell_h * static_cast<double>(r + 1);
      const int category = map.category[i];
      const Colour fill = category >= 0
                              ? kPalette[static_cast<std::size_t>(category) % std::size(kPalette)]
                              : Colour{1, 1, 1};
      cairo_set_source_rgb(cr, fill.r, fill.g, fill.b);
      cairo_rectangle(cr, x, y, cell_w, cell_h);
      cairo_fill_preserve(cr);
      cairo_set_source_rgb(cr, 1, 1, 1);
      cairo_set_line_width(cr, 2 * scale);
      cairo_stroke(cr);
      if (!map.cell_text.empty() && !map.cell_text[i].empty()) {
        cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
        text(cr, map.cell_text[i], x + cell_w / 2, y + cell_h / 2, 0.5, 0.5);
      }
    }
  cairo_set_source_rgb(cr, 0, 0, 0);
  font(cr, 15 * scale, false);
  for (std::size_t c = 0; c < map.columns.size(); ++c)
    text(cr, map.columns[c], left + cell_w * (static_cast<double>(c) + 0.5), bottom + 8 * scale,
         0.5, 0);
  for (std::size_t r = 0; r < map.rows.size(); ++r)
    text(cr, map.rows[r], left - 10 * scale, bottom - cell_h * (static_cast<double>(r) + 0.5), 1,
         0.5);
  font(cr, 17 * scale, false);
  text(cr, map.x_label, (left + right) / 2, height - 22 * scale, 0.5, 1);
  cairo_save(cr);
  cairo_translate(cr, 28 * scale, (top + bottom) / 2);
  cairo_rotate(cr, -1.5707963267948966);
  text(cr, map.y_label, 0, 0, 0.5, 0.5);
  cairo_restore(cr);

  font(cr, 15 * scale, false);
  for (std::size_t k = 0; k < map.categories.size(); ++k) {
    const double y = top + 28 * scale * static_cast<double>(k);
    const Colour fill = kPalette[k % std::size(kPalette)];
    cairo_set_source_rgb(cr, fill.r, fill.g, fill.b);
    cairo_rectangle(cr, right + 20 * scale, y, 20 * scale, 20 * scale);
    cairo_fill(cr);
    cairo_set_source_rgb(cr, 0, 0, 0);
    text(cr, map.categories[k], right + 48 * scale, y + 10 * scale, 0, 0.5);
  }
}

}  // namespace

std::string write_png(const HeatMap& map, const std::string& path, int width, int height) {
  const auto failed = [&path](const std::string& what) {
    return "cannot write heat map '" + path + "': " + what;
  };
  const std::size_t cells = map.rows.size() * map.columns.size();
  if (cells == 0) return failed("it has no cells");
  if (map.category.size() != cells || (!map.cell_text.empty() && map.cell_text.size() != cells))
    return failed("it has " + std::to_string(map.rows.size()) + " x " +
                  std::to_string(map.columns.size()) + " cells but " +
                  std::to_string(map.category.size()) + " categories");
  for (int category : map.category)
    if (category >= static_cast<int>(map.categories.size()))
      return failed("a cell names no category");
  if (width < 320 || height < 200 || width > 16384 || height > 16384)
    return failed("image size out of range");
  const std::unique_ptr<cairo_surface_t, decltype(&cairo_surface_destroy)> surface(
      cairo_image_surface_create(CAIRO_FORMAT_RGB24, width, height), cairo_surface_destroy);
  const std::unique_ptr<cairo_t, decltype(&cairo_destroy)> cr(cairo_create(surface.get()),
                                                              cairo_destroy);
  draw(cr.get(), map, width, height);
  cairo_surface_flush(surface.get());
  if (const std::string problem = write_surface_png(surface.get(), path); !problem.empty())
    return failed(problem);
  return {};
}

}  // namespace flutterscan::plot
