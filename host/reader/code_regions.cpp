#include "reader/code_regions.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace flutterscan::reader {
namespace {

constexpr int kCell = 16;
constexpr double kMinContrast = 0.04;
/// Changes a busy cell's samples make per kCell px, counting both directions
/// (each change between its darkest and brightest): a code's modules make
/// several, an edge at most one.
constexpr double kMinChanges = 1.5;
constexpr double kNoisePercentile = 0.2;
/// A busy cell's contrast is at least this many times the noise: a cell of
/// noise alone (its spread's estimate from 64 samples varies by about 18%, and
/// the flattest fifth's is low) stays well below it.
constexpr double kNoiseMultiple = 1.5;
constexpr int kMinCells = 6;
/// Regions side by side along the rows within this many px of each other,
/// sharing at least half the rows of the shorter, are one code: a linear
/// code's widest bars and spaces (4 modules) leave cells that change too
/// seldom to look busy, and the code fell into pieces none of which holds it.
constexpr int kJoinGap = 8 * kCell;

/// bar_likeness()'s lag: bars run on this far; noise (each row deblurred on
/// its own) and text's strokes (a letter's height, a few times this) less.
constexpr int kLag = 8;

/// Rows sampled: every kRowStep-th, each averaged with the row after it.
constexpr int kRowStep = 4;

struct CellStats {
  double sum = 0, square = 0, along = 0, across = 0;
  float low = 1e30f, high = -1e30f;
  int samples = 0, along_steps = 0;
  int rows = 0, rows_changing = 0;  ///< sampled rows, and those that change along the cell
};

}  // namespace

std::vector<LabelRegion> find_code_regions(const imaging::Plane& latent) {
  std::vector<LabelRegion> regions;
  if (latent.width < kCell || latent.height < kCell) return regions;
  const int cols = (latent.width + kCell - 1) / kCell, rows = (latent.height + kCell - 1) / kCell;
  std::vector<CellStats> cells(static_cast<std::size_t>(cols) * rows);
  // Every kRowStep-th row averaged with the next: print is the same in two
  // neighbouring rows (a linear code's bars run across them, a matrix code's
  // modules span more than one) and the deblurred noise is not (rows are
  // deblurred on their own), so the pair halves the noise's variance and keeps
  // the print: low-contrast print on a textured carton in dim light stood
  // under the threshold a cell at a time. The pair's samples and steps along
  // x, and the steps between its two rows (one pixel across: a step across
  // that spans kRowStep rows would count an edge along the rows as several).
  std::vector<float> pair(static_cast<std::size_t>(latent.width));
  for (int y = 0; y + 1 < latent.height; y += kRowStep) {
    const float* row = latent.row(y).data();
    const float* next = latent.row(y + 1).data();
    for (int x = 0; x < latent.width; ++x) pair[x] = 0.5f * (row[x] + next[x]);
    CellStats* line = &cells[static_cast<std::size_t>(y / kCell) * cols];
    for (int cx = 0; cx < cols; ++cx) {
      const int x0 = cx * kCell, x1 = std::min(latent.width, x0 + kCell);
      const int x_steps_end = std::min(x1, latent.width - 1);
      // Vectorised reductions (partial sums, so rounding differs from a serial sum).
      float sum = 0, square = 0, along = 0, across = 0, low = pair[x0], high = pair[x0];
#pragma omp simd reduction(+ : sum, square, across) reduction(min : low) reduction(max : high)
      for (int x = x0; x < x1; ++x) {
        const float v = pair[x];
        sum += v;
        square += v * v;
        low = std::min(low, v);
        high = std::max(high, v);
        across += std::abs(next[x] - row[x]);
      }
#pragma omp simd reduction(+ : along)
      for (int x = x0; x < x_steps_end; ++x) along += std::abs(pair[x + 1] - pair[x]);
      CellStats& c = line[cx];
      c.sum += sum;
      c.square += square;
      c.low = std::min(c.low, low);
      c.high = std::max(c.high, high);
      c.samples += x1 - x0;
      c.along += along;
      c.along_steps += x_steps_end - x0;
      ++c.rows;
      c.rows_changing += along > 0 ? 1 : 0;
      c.across += across;
    }
  }
  std::vector<double> spread(cells.size(), 0.0), steps(cells.size(), 0.0);
  for (std::size_t i = 0; i < cells.size(); ++i) {
    const CellStats& c = cells[i];
    if (c.samples == 0) continue;
    const double mean = c.sum / c.samples;
    spread[i] = std::sqrt(std::max(0.0, c.square / c.samples - mean * mean));
    steps[i] = c.across / c.samples + (c.along_steps > 0 ? c.along / c.along_steps : 0.0);
  }
  // The frame's noise: its flattest cells' spread and steps, among the cells
  // whose every sampled row changes along the cell. A constant row, one the
  // deblur found flat and filled or clipped light, says nothing about the
  // noise, and a cell that mixes such rows with noisy ones is flatter than the
  // noise: the single rows among the flat ones that the flat-row test lets
  // through (about one in a hundred) made such cells all across the frame,
  // they were the flattest fifth, the noise came out far too low, and at 300 e-
  // the belt beside the labels was busy from one edge of the frame to the
  // other. (If no cell changes in every sampled row: those that change at all.)
  std::vector<double> noisy_spread, noisy_steps;
  for (const bool every_row : {true, false}) {
    for (std::size_t i = 0; i < cells.size(); ++i) {
      const CellStats& c = cells[i];
      if (every_row ? c.rows > 0 && c.rows_changing == c.rows : c.along > 0)
        noisy_spread.push_back(spread[i]), noisy_steps.push_back(steps[i]);
    }
    if (!noisy_spread.empty()) break;
  }
  auto percentile = [](std::vector<double> values) {
    if (values.empty()) return 0.0;
    const auto nth =
        values.begin() + static_cast<std::ptrdiff_t>(kNoisePercentile * (values.size() - 1));
    std::nth_element(values.begin(), nth, values.end());
    return *nth;
  };
  const double noise = percentile(std::move(noisy_spread)),
               noise_steps = percentile(std::move(noisy_steps));
  const double need = std::max(kMinContrast, kNoiseMultiple * noise);
  std::vector<char> busy(cells.size(), 0);
  int busy_count = 0;
  for (std::size_t i = 0; i < cells.size(); ++i) {
    const double contrast = std::sqrt(std::max(0.0, spread[i] * spread[i] - noise * noise));
    // The range less what noise adds to it (about 4 noise deviations over a cell's samples).
    const double range = std::max(0.0, cells[i].high - cells[i].low - 4 * noise);
    if (contrast >= need && steps[i] - noise_steps >= kMinChanges / kCell * range) {
      busy[i] = 1;
      ++busy_count;
    }
  }
  if (busy_count < kMinCells) return regions;
  // Grown by one cell, joined where they touch (4-neighbours); each region's busy cells counted.
  std::vector<char> grown(cells.size(), 0);
  for (int cy = 0; cy < rows; ++cy)
    for (int cx = 0; cx < cols; ++cx) {
      if (!busy[static_cast<std::size_t>(cy) * cols + cx]) continue;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int gx = cx + dx, gy = cy + dy;
          if (gx >= 0 && gx < cols && gy >= 0 && gy < rows)
            grown[static_cast<std::size_t>(gy) * cols + gx] = 1;
        }
    }
  std::vector<int> label(cells.size(), -1);
  std::vector<int> stack;
  for (std::size_t seed = 0; seed < cells.size(); ++seed) {
    if (!grown[seed] || label[seed] >= 0) continue;
    const int id = static_cast<int>(seed);
    int x0 = cols, x1 = -1, y0 = rows, y1 = -1, count = 0;
    stack.assign(1, id);
    label[seed] = id;
    while (!stack.empty()) {
      const int at = stack.back();
      stack.pop_back();
      const int cx = at % cols, cy = at / cols;
      if (busy[static_cast<std::size_t>(at)]) {  // the extent: the busy cells only
        x0 = std::min(x0, cx), x1 = std::max(x1, cx), y0 = std::min(y0, cy), y1 = std::max(y1, cy);
        ++count;
      }
      const int neighbours[4][2] = {{cx - 1, cy}, {cx + 1, cy}, {cx, cy - 1}, {cx, cy + 1}};
      for (const auto& [nx, ny] : neighbours) {
        if (nx < 0 || nx >= cols || ny < 0 || ny >= rows) continue;
        const std::size_t n = static_cast<std::size_t>(ny) * cols + nx;
        if (!grown[n] || label[n] >= 0) continue;
        label[n] = id;
        stack.push_back(static_cast<int>(n));
      }
    }
    if (count < kMinCells) continue;
    LabelRegion r;
    r.begin = x0 * kCell;
    r.end = std::min(latent.width, (x1 + 1) * kCell);
    r.across_begin = y0 * kCell;
    r.across_end = std::min(latent.height, (y1 + 1) * kCell);
    r.cut = r.begin == 0 || r.end == latent.width;
    regions.push_back(r);
  }
  std::sort(regions.begin(), regions.end(),
            [](const LabelRegion& a, const LabelRegion& b) { return a.begin < b.begin; });
  auto one_code = [](const LabelRegion& a, const LabelRegion& b) {
    const int shared =
        std::min(a.across_end, b.across_end) - std::max(a.across_begin, b.across_begin);
    const int shorter = std::min(a.across_end - a.across_begin, b.across_end - b.across_begin);
    const int gap = std::max(a.begin, b.begin) - std::min(a.end, b.end);  // < 0: they overlap
    return 2 * shared >= shorter && gap <= kJoinGap;
  };
  for (bool joined = true; joined;) {  // until no two are one code
    joined = false;
    for (std::size_t i = 0; i < regions.size() && !joined; ++i)
      for (std::size_t j = i + 1; j < regions.size() && !joined; ++j) {
        LabelRegion& a = regions[i];
        const LabelRegion& b = regions[j];
        if (!one_code(a, b)) continue;
        a.begin = std::min(a.begin, b.begin);
        a.end = std::max(a.end, b.end);
        a.across_begin = std::min(a.across_begin, b.across_begin);
        a.across_end = std::max(a.across_end, b.across_end);
        a.cut = a.cut || b.cut;
        regions.erase(regions.begin() + static_cast<std::ptrdiff_t>(j));
        joined = true;
      }
  }
  return regions;
}

std::vector<double> bar_likeness(const imaging::Plane& latent,
                                 std::span<const LabelRegion> regions) {
  constexpr int kStep = 4;
  std::vector<double> out;
  for (const LabelRegion& r : regions) {
    const int top = r.rows_measured() ? r.across_begin : 0;
    const int bottom = r.rows_measured() ? r.across_end : latent.height;
    const int x0 = std::max(1, r.begin), x1 = std::min(latent.width - 1, r.end);
    const int y0 = std::max(1, top), y1 = std::min(latent.height - 1, bottom);
    // Steps along the rows against the same kLag rows on, and across against kLag columns on.
    double gx_cross = 0, gx_here = 0, gx_there = 0, gy_cross = 0, gy_here = 0, gy_there = 0;
    for (int y = y0; y + kLag < y1; y += kStep)
      for (int x = x0; x + kLag < x1; x += kStep) {
        const double gx = latent.at(x + 1, y) - latent.at(x - 1, y);
        const double gx_on = latent.at(x + 1, y + kLag) - latent.at(x - 1, y + kLag);
        const double gy = latent.at(x, y + 1) - latent.at(x, y - 1);
        const double gy_on = latent.at(x + kLag, y + 1) - latent.at(x + kLag, y - 1);
        gx_cross += gx * gx_on;
        gx_here += gx * gx;
        gx_there += gx_on * gx_on;
        gy_cross += gy * gy_on;
        gy_here += gy * gy;
        gy_there += gy_on * gy_on;
      }
    const double bars_across =
        gx_here > 0 && gx_there > 0 ? gx_cross / std::sqrt(gx_here * gx_there) : 0;
    const double bars_along =
        gy_here > 0 && gy_there > 0 ? gy_cross / std::sqrt(gy_here * gy_there) : 0;
    out.push_back(std::max({0.0, bars_across, bars_along}));
  }
  return out;
}

std::vector<LabelRegion> regions_to_read(std::span<const LabelRegion> paper,
                                         std::span<const LabelRegion> code) {
  std::vector<LabelRegion> out(paper.begin(), paper.end());
  for (const LabelRegion& c : code) {
    const bool inside = std::any_of(paper.begin(), paper.end(),
                                    [&](const LabelRegion& p) { return p.contains(c); });
    if (!inside) out.push_back(c);
  }
  return out;
}

}  // namespace flutterscan::reader
