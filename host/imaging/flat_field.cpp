#include "imaging/flat_field.hpp"

#include <algorithm>
#include <cmath>

namespace flutterscan::imaging {
namespace {

double median(std::vector<float> values) {
  if (values.empty()) return 0;
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

double median(std::vector<double> values) {
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

/// Median of `plane` over tile (tx, ty) of a tiles_x x tiles_y grid.
double tile_median(const Plane& plane, int tx, int ty, int tiles_x, int tiles_y) {
  std::vector<float> values;
  const int x0 = plane.width * tx / tiles_x, x1 = plane.width * (tx + 1) / tiles_x;
  const int y0 = plane.height * ty / tiles_y, y1 = plane.height * (ty + 1) / tiles_y;
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) values.push_back(plane.at(x, y));
  return median(std::move(values));
}

/// Inverse of the n x n row-major matrix `a` by Gauss-Jordan with partial pivoting;
/// false if singular.
bool invert(std::vector<double> a, int n, std::vector<double>& inverse) {
  inverse.assign(static_cast<std::size_t>(n * n), 0.0);
  for (int i = 0; i < n; ++i) inverse[static_cast<std::size_t>(i * n + i)] = 1;
  auto at = [n](std::vector<double>& m, int r, int c) -> double& {
    return m[static_cast<std::size_t>(r * n + c)];
  };
  double scale = 0;
  for (double v : a) scale = std::max(scale, std::abs(v));
  for (int col = 0; col < n; ++col) {
    int pivot = col;
    for (int r = col + 1; r < n; ++r)
      if (std::abs(at(a, r, col)) > std::abs(at(a, pivot, col))) pivot = r;
    if (!(std::abs(at(a, pivot, col)) > 1e-12 * scale)) return false;
    for (int c = 0; c < n; ++c) {
      std::swap(at(a, col, c), at(a, pivot, c));
      std::swap(at(inverse, col, c), at(inverse, pivot, c));
    }
    const double d = at(a, col, col);
    for (int c = 0; c < n; ++c) {
      at(a, col, c) /= d;
      at(inverse, col, c) /= d;
    }
    for (int r = 0; r < n; ++r) {
      if (r == col) continue;
      const double f = at(a, r, col);
      for (int c = 0; c < n; ++c) {
        at(a, r, c) -= f * at(a, col, c);
        at(inverse, r, c) -= f * at(inverse, col, c);
      }
    }
  }
  return true;
}

/// The correction C = A_ref A_tile^-1 of every tile (n x n each), or an error.
Result<std::vector<double>, std::string> corrections(const FlatField& flat) {
  const int n = flat.channels;
  const auto size = static_cast<std::size_t>(n * n);
  std::vector<double> out;
  std::vector<double> inverse;
  for (int t = 0; t < flat.tiles_x * flat.tiles_y; ++t) {
    const std::vector<double> a(flat.mixing.begin() + static_cast<std::ptrdiff_t>(t * size),
                                flat.mixing.begin() + static_cast<std::ptrdiff_t>((t + 1) * size));
    if (!invert(a, n, inverse))
      return Result<std::vector<double>, std::string>::failure(
          "the LED mixing of flat-field tile " + std::to_string(t) + " is singular");
    for (int r = 0; r < n; ++r)
      for (int c = 0; c < n; ++c) {
        double v = 0;
        for (int k = 0; k < n; ++k)
          v += flat.reference[static_cast<std::size_t>(r * n + k)] *
               inverse[static_cast<std::size_t>(k * n + c)];
        out.push_back(v);
      }
  }
  return Result<std::vector<double>, std::string>::success(std::move(out));
}

/// Bilinear position between tile centres: lower index and weight of the upper one.
void tile_position(int pixel, int pixels, int tiles, int& lower, double& weight) {
  const double u = (pixel + 0.5) * tiles / pixels - 0.5;
  const double clamped = std::clamp(u, 0.0, static_cast<double>(tiles - 1));
  lower = std::min(tiles - 1, static_cast<int>(std::floor(clamped)));
  weight = clamped - lower;
}

}  // namespace

Result<FlatField, std::string> measure_flat_field(const Image& dark, std::span<const Image> lit,
                                                  int tiles_x, int tiles_y, double full_scale_dn) {
  using Out = Result<FlatField, std::string>;
  if (tiles_x < 1 || tiles_y < 1 || tiles_x > 64 || tiles_y > 64)
    return Out::failure("the flat-field grid must be 1..64 tiles each way");
  const int channels = dark.channel_count();
  if (channels == 0) return Out::failure("the dark frame is empty");
  if (static_cast<int>(lit.size()) != channels)
    return Out::failure(
        "the flat field needs one frame per LED, as many as the camera has "
        "channels (" +
        std::to_string(channels) + "), not " + std::to_string(lit.size()));
  if (dark.width() < 4 * tiles_x || dark.height() < 4 * tiles_y)
    return Out::failure("a " + std::to_string(tiles_x) + "x" + std::to_string(tiles_y) +
                        " grid needs tiles of 4 px or more: the frame is too small");
  FlatField flat;
  flat.width = dark.width();
  flat.height = dark.height();
  flat.tiles_x = tiles_x;
  flat.tiles_y = tiles_y;
  flat.channels = channels;
  flat.leds = channels;
  for (std::size_t k = 0; k < lit.size(); ++k)
    if (lit[k].channel_count() != channels || lit[k].width() != dark.width() ||
        lit[k].height() != dark.height())
      return Out::failure("the frame of LED " + std::to_string(k) +
                          " does not match the dark frame's size and channels");
  for (int ty = 0; ty < tiles_y; ++ty)
    for (int tx = 0; tx < tiles_x; ++tx)
      for (int c = 0; c < channels; ++c) {
        const double black =
            tile_median(dark.channels[static_cast<std::size_t>(c)], tx, ty, tiles_x, tiles_y);
        for (int k = 0; k < channels; ++k) {
          const double level =
              tile_median(lit[static_cast<std::size_t>(k)].channels[static_cast<std::size_t>(c)],
                          tx, ty, tiles_x, tiles_y);
          if (level >= 0.98 * full_scale_dn)
            return Out::failure("the frame of LED " + std::to_string(k) + " saturates channel " +
                                std::to_string(c) + " in tile (" + std::to_string(tx) + ", " +
                                std::to_string(ty) + ")");
          flat.mixing.push_back(std::max(0.0, level - black));
        }
      }
  const auto n = static_cast<std::size_t>(channels * channels);
  const auto tiles = static_cast<std::size_t>(tiles_x * tiles_y);
  for (std::size_t e = 0; e < n; ++e) {
    std::vector<double> entry;
    for (std::size_t t = 0; t < tiles; ++t) entry.push_back(flat.mixing[t * n + e]);
    flat.reference.push_back(median(entry));
  }
  for (int c = 0; c < channels; ++c) {
    const auto d = static_cast<std::size_t>(c * channels + c);
    if (!(flat.reference[d] > 0.01 * full_scale_dn))
      return Out::failure("LED " + std::to_string(c) +
                          " barely lights its own channel (under 1% of full scale): is it "
                          "connected, and is the white target under the camera?");
    for (std::size_t t = 0; t < tiles; ++t)
      flat.largest_deviation = std::max(flat.largest_deviation,
                                        std::abs(flat.mixing[t * n + d] / flat.reference[d] - 1));
  }
  if (auto check = corrections(flat); !check.ok()) return Out::failure(check.error());
  return Out::success(flat);
}

std::string apply_flat_field(Image& electrons, const FlatField& flat) {
  if (electrons.channel_count() != flat.channels || electrons.width() != flat.width ||
      electrons.height() != flat.height)
    return "the flat field was measured on " + std::to_string(flat.width) + "x" +
           std::to_string(flat.height) + " frames of " + std::to_string(flat.channels) +
           " channels; this frame is " + std::to_string(electrons.width()) + "x" +
           std::to_string(electrons.height()) + " of " + std::to_string(electrons.channel_count());
  const auto correction = corrections(flat);
  if (!correction.ok()) return correction.error();
  const int n = flat.channels;
  const auto size = static_cast<std::size_t>(n * n);
  const auto& c = correction.value();
  std::vector<double> here(size), y(static_cast<std::size_t>(n));
  for (int row = 0; row < flat.height; ++row) {
    int ty;
    double wy;
    tile_position(row, flat.height, flat.tiles_y, ty, wy);
    const int ty1 = std::min(ty + 1, flat.tiles_y - 1);
    for (int col = 0; col < flat.width; ++col) {
      int tx;
      double wx;
      tile_position(col, flat.width, flat.tiles_x, tx, wx);
      const int tx1 = std::min(tx + 1, flat.tiles_x - 1);
      const double* c00 = &c[static_cast<std::size_t>(ty * flat.tiles_x + tx) * size];
      const double* c01 = &c[static_cast<std::size_t>(ty * flat.tiles_x + tx1) * size];
      const double* c10 = &c[static_cast<std::size_t>(ty1 * flat.tiles_x + tx) * size];
      const double* c11 = &c[static_cast<std::size_t>(ty1 * flat.tiles_x + tx1) * size];
      for (std::size_t e = 0; e < size; ++e)
        here[e] =
            (1 - wy) * ((1 - wx) * c00[e] + wx * c01[e]) + wy * ((1 - wx) * c10[e] + wx * c11[e]);
      for (int k = 0; k < n; ++k)
        y[static_cast<std::size_t>(k)] =
            electrons.channels[static_cast<std::size_t>(k)].at(col, row);
      for (int r = 0; r < n; ++r) {
        double v = 0;
        for (int k = 0; k < n; ++k)
          v += here[static_cast<std::size_t>(r * n + k)] * y[static_cast<std::size_t>(k)];
        electrons.channels[static_cast<std::size_t>(r)].at(col, row) = static_cast<float>(v);
      }
    }
  }
  return {};
}

nlohmann::json flat_field_to_json(const FlatField& flat) {
  return {{"format", "flutterscan-flat-field"},
          {"version", 1},
          {"width", flat.width},
          {"height", flat.height},
          {"tiles", {flat.tiles_x, flat.tiles_y}},
          {"channels", flat.channels},
          {"leds", flat.leds},
          {"mixing_dn", flat.mixing},
          {"reference_dn", flat.reference},
          {"largest_deviation", flat.largest_deviation}};
}

Result<FlatField, std::string> flat_field_from_json(const nlohmann::json& json) {
  using Out = Result<FlatField, std::string>;
  try {
    if (json.at("format") != "flutterscan-flat-field")
      return Out::failure("\"format\" is not \"flutterscan-flat-field\"");
    if (json.at("version") != 1)
      return Out::failure("\"version\" " + json.at("version").dump() + " is not 1");
    FlatField flat;
    flat.width = json.at("width").get<int>();
    flat.height = json.at("height").get<int>();
    flat.tiles_x = json.at("tiles").at(0).get<int>();
    flat.tiles_y = json.at("tiles").at(1).get<int>();
    flat.channels = json.at("channels").get<int>();
    flat.leds = json.at("leds").get<int>();
    flat.mixing = json.at("mixing_dn").get<std::vector<double>>();
    flat.reference = json.at("reference_dn").get<std::vector<double>>();
    flat.largest_deviation = json.value("largest_deviation", 0.0);
    const auto n = static_cast<std::size_t>(flat.channels * flat.leds);
    if (flat.width < 1 || flat.height < 1 || flat.tiles_x < 1 || flat.tiles_y < 1 ||
        flat.channels < 1 || flat.channels > 4 || flat.leds != flat.channels)
      return Out::failure("sizes out of range (width, height, tiles, channels = leds 1..4)");
    if (flat.reference.size() != n ||
        flat.mixing.size() != n * static_cast<std::size_t>(flat.tiles_x * flat.tiles_y))
      return Out::failure("\"mixing_dn\" or \"reference_dn\" has the wrong number of values");
    for (double v : flat.mixing)
      if (!std::isfinite(v) || v < 0)
        return Out::failure("\"mixing_dn\" holds a value < 0 or not finite");
    if (auto check = corrections(flat); !check.ok()) return Out::failure(check.error());
    return Out::success(flat);
  } catch (const nlohmann::json::exception& e) {
    return Out::failure(std::string("missing or mistyped field: ") + e.what());
  }
}

}  // namespace flutterscan::imaging
