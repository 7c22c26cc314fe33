#include "imaging/crosstalk_calibration.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <sstream>

namespace flutterscan::imaging {
namespace {

/// Median of the middle half of `plane` in each direction.
double centre_median(const Plane& plane) {
  std::vector<float> values;
  for (int y = plane.height / 4; y < plane.height * 3 / 4; ++y)
    for (int x = plane.width / 4; x < plane.width * 3 / 4; ++x) values.push_back(plane.at(x, y));
  if (values.empty()) return 0;
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

/// Eigenvalues of a symmetric n x n matrix (n <= 4) by cyclic Jacobi rotations.
std::vector<double> symmetric_eigenvalues(std::vector<double> a, int n) {
  auto at = [&](int r, int c) -> double& { return a[static_cast<std::size_t>(r * n + c)]; };
  for (int sweep = 0; sweep < 60; ++sweep) {
    double off = 0;
    for (int p = 0; p < n; ++p)
      for (int q = p + 1; q < n; ++q) off += at(p, q) * at(p, q);
    if (off < 1e-30) break;
    for (int p = 0; p < n; ++p)
      for (int q = p + 1; q < n; ++q) {
        if (std::abs(at(p, q)) < 1e-300) continue;
        const double theta = (at(q, q) - at(p, p)) / (2 * at(p, q));
        const double t =
            (theta >= 0 ? 1.0 : -1.0) / (std::abs(theta) + std::sqrt(theta * theta + 1));
        const double c = 1 / std::sqrt(t * t + 1), s = t * c;
        for (int k = 0; k < n; ++k) {  // columns p, q
          const double akp = at(k, p), akq = at(k, q);
          at(k, p) = c * akp - s * akq;
          at(k, q) = s * akp + c * akq;
        }
        for (int k = 0; k < n; ++k) {  // rows p, q
          const double apk = at(p, k), aqk = at(q, k);
          at(p, k) = c * apk - s * aqk;
          at(q, k) = s * apk + c * aqk;
        }
      }
  }
  std::vector<double> values;
  for (int i = 0; i < n; ++i) values.push_back(at(i, i));
  return values;
}

}  // namespace

double condition_number(const std::vector<double>& matrix, int rows, int cols) {
  // Singular values squared = eigenvalues of M^T M (cols x cols).
  std::vector<double> gram(static_cast<std::size_t>(cols * cols), 0.0);
  for (int i = 0; i < cols; ++i)
    for (int j = 0; j < cols; ++j)
      for (int r = 0; r < rows; ++r)
        gram[static_cast<std::size_t>(i * cols + j)] +=
            matrix[static_cast<std::size_t>(r * cols + i)] *
            matrix[static_cast<std::size_t>(r * cols + j)];
  const auto eigen = symmetric_eigenvalues(gram, cols);
  const auto [lowest, highest] = std::minmax_element(eigen.begin(), eigen.end());
  if (!(*lowest > 1e-15 * *highest)) return std::numeric_limits<double>::infinity();
  return std::sqrt(*highest / *lowest);
}

Result<CrosstalkCalibration, std::string> calibrate_crosstalk(const Image& dark,
                                                              std::span<const Image> lit,
                                                              double full_scale_dn) {
  using Out = Result<CrosstalkCalibration, std::string>;
  const int channels = dark.channel_count();
  if (channels == 0 || dark.width() < 4 || dark.height() < 4)
    return Out::failure("the dark frame is empty");
  if (lit.empty()) return Out::failure("no frame with an LED lit alone");
  if (lit.size() > 4) return Out::failure("at most 4 LEDs");
  CrosstalkCalibration out;
  out.channels = channels;
  out.leds = static_cast<int>(lit.size());
  for (const auto& plane : dark.channels) out.black_level_dn.push_back(centre_median(plane));
  std::vector<double> a(static_cast<std::size_t>(channels * out.leds));
  for (int k = 0; k < out.leds; ++k) {
    const Image& frame = lit[static_cast<std::size_t>(k)];
    if (frame.channel_count() != channels || frame.width() != dark.width() ||
        frame.height() != dark.height())
      return Out::failure("the frame of LED " + std::to_string(k) +
                          " does not match the dark frame's size and channels");
    double column = 0;
    for (int c = 0; c < channels; ++c) {
      const double level = centre_median(frame.channels[static_cast<std::size_t>(c)]);
      if (level >= 0.98 * full_scale_dn)
        return Out::failure("the frame of LED " + std::to_string(k) + " saturates channel " +
                            std::to_string(c) + ": shorten the exposure or dim the LED");
      const double value = std::max(0.0, level - out.black_level_dn[static_cast<std::size_t>(c)]);
      a[static_cast<std::size_t>(c * out.leds + k)] = value;
      column += value;
    }
    if (!(column > 0.01 * full_scale_dn))
      return Out::failure("LED " + std::to_string(k) +
                          " barely lights the target (under 1% of full scale over every "
                          "channel): is it connected, and is the white target under the camera?");
    out.led_strength_dn.push_back(column);
  }
  out.crosstalk = a;
  for (int c = 0; c < channels; ++c)
    for (int k = 0; k < out.leds; ++k)
      out.crosstalk[static_cast<std::size_t>(c * out.leds + k)] /=
          out.led_strength_dn[static_cast<std::size_t>(k)];
  double mean_row = 0;
  for (int c = 0; c < channels; ++c) {
    double row = 0;
    for (int k = 0; k < out.leds; ++k) row += a[static_cast<std::size_t>(c * out.leds + k)];
    out.channel_gain.push_back(row);
    mean_row += row / channels;
  }
  for (double& g : out.channel_gain) g = mean_row > 0 ? g / mean_row : 0;
  out.condition_number = condition_number(out.crosstalk, channels, out.leds);
  if (out.condition_number > kPoorSeparationCondition) {
    std::ostringstream text;
    text << "the crosstalk matrix's condition number is " << out.condition_number << " (above "
         << kPoorSeparationCondition
         << "): unmixing the LEDs amplifies noise that much; LEDs whose colours match the "
            "camera's filters better separate better";
    out.warning = text.str();
  }
  return Out::success(out);
}

}  // namespace flutterscan::imaging
