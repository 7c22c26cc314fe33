#include "imaging/photon_transfer.hpp"

#include <cmath>

namespace flutterscan::imaging {
namespace {

struct PairStatistics {
  double mean = 0, temporal_variance = 0;
};

PairStatistics pair_statistics(const Plane& a, const Plane& b) {
  const std::size_t n = a.pixels.size();
  double sum = 0, difference_sum = 0;
  for (std::size_t i = 0; i < n; ++i) {
    sum += static_cast<double>(a.pixels[i]) + b.pixels[i];
    difference_sum += static_cast<double>(a.pixels[i]) - b.pixels[i];
  }
  const double difference_mean = difference_sum / static_cast<double>(n);
  double squares = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double d = static_cast<double>(a.pixels[i]) - b.pixels[i] - difference_mean;
    squares += d * d;
  }
  return {sum / (2.0 * static_cast<double>(n)), squares / static_cast<double>(n - 1) / 2.0};
}

bool same_shape(const Image& a, const Image& b) {
  return a.channel_count() == b.channel_count() && a.width() == b.width() &&
         a.height() == b.height();
}

}  // namespace

Result<PhotonTransfer, std::string> photon_transfer(const FlatPair& dark,
                                                    std::span<const FlatPair> flats,
                                                    double full_scale_dn) {
  using Out = Result<PhotonTransfer, std::string>;
  if (dark.first.channel_count() == 0 || dark.first.width() * dark.first.height() < 2)
    return Out::failure("the dark pair is empty");
  if (!same_shape(dark.first, dark.second))
    return Out::failure("the two dark frames differ in size or channels");
  for (std::size_t i = 0; i < flats.size(); ++i)
    if (!same_shape(flats[i].first, dark.first) || !same_shape(flats[i].second, dark.first))
      return Out::failure("flat pair " + std::to_string(i + 1) +
                          " differs in size or channels from the dark pair");
  PhotonTransfer out;
  const int channels = dark.first.channel_count();
  for (int c = 0; c < channels; ++c) {
    const auto ci = static_cast<std::size_t>(c);
    const auto dark_stats = pair_statistics(dark.first.channels[ci], dark.second.channels[ci]);
    out.black_level_dn.push_back(dark_stats.mean);
    std::vector<TransferPoint> points;
    double xy = 0, xx = 0;
    int fitted = 0;
    for (const FlatPair& pair : flats) {
      const auto stats = pair_statistics(pair.first.channels[ci], pair.second.channels[ci]);
      TransferPoint p;
      p.mean_dn = stats.mean - dark_stats.mean;
      p.variance_dn2 = stats.temporal_variance;
      const double saturation_range = full_scale_dn - dark_stats.mean;
      p.fitted = p.mean_dn > 0 && p.mean_dn < 0.7 * saturation_range;
      if (p.fitted) {
        const double y = p.variance_dn2 - dark_stats.temporal_variance;
        xy += p.mean_dn * y;
        xx += p.mean_dn * p.mean_dn;
        ++fitted;
      }
      points.push_back(p);
    }
    if (fitted < 2)
      return Out::failure("channel " + std::to_string(c) + ": only " + std::to_string(fitted) +
                          " flat pair(s) lie between dark and 70% of saturation; the fit needs "
                          "two or more levels");
    const double k = xy / xx;  // DN per e-
    if (!(k > 0))
      return Out::failure("channel " + std::to_string(c) +
                          ": the temporal variance does not grow with the signal (is the light "
                          "changing between levels, or the camera's gain automatic?)");
    out.gain_e_per_dn.push_back(1.0 / k);
    out.read_noise_e.push_back(std::sqrt(std::max(0.0, dark_stats.temporal_variance - 1.0 / 12)) /
                               k);
    out.points.push_back(std::move(points));
  }
  return Out::success(out);
}

}  // namespace flutterscan::imaging
