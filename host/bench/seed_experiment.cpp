#include "bench/seed_experiment.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "codes/library.hpp"
#include "imaging/metrics.hpp"
#include "imaging/richardson_lucy.hpp"
#include "sim/scene.hpp"

namespace flutterscan::bench {
namespace {

using imaging::Plane;

constexpr int kSlots = 52;
constexpr double kSeedNoise = 0.01;  // the seed's nf
constexpr double kElectrons = 3000;  // EMVA: white object, whole exposure
constexpr double kReadNoise = 4;

/// One exposure of the experiment: a 0/1 window and the seed's duty factor dc.
struct Exposure {
  std::vector<double> window;
  double dc;
};

struct Row {
  std::string name;
  std::vector<Exposure> exposures;  ///< deblurred separately, results averaged
};

std::vector<double> ones(int n) {
  return std::vector<double>(static_cast<std::size_t>(n), 1.0);
}

std::vector<double> bits(const LedCode& code, int led) {
  std::vector<double> out;
  for (int t = 0; t < code.length(); ++t) out.push_back(code.is_on(t, led) ? 1.0 : 0.0);
  return out;
}

std::vector<Row> seed_rows() {
  const LedCode raskar = codes::to_code(*codes::find_library_code("raskar"));
  // The seed's triplet has duty factors 16/52, 18/52, 18/52: the avg-min code.
  const LedCode triplet = codes::to_code(*codes::find_library_code("seed-avgmin"));
  Row triplet_row{"triplet (avg-min code), averaged", {}};
  for (int led = 0; led < 3; ++led)
    triplet_row.exposures.push_back(
        {bits(triplet, led), triplet.on_slots(led) / static_cast<double>(kSlots)});
  // The seed's Raskar exposures: 50% duty cycle and a 50% shutter: dc 0.25.
  return {
      {"flat 52", {{ones(kSlots), 1.0}}},
      {"Raskar", {{bits(raskar, 0), 0.25}}},
      {"Raskar + inverted, averaged",
       {{bits(raskar, 0), 0.25}, {bits(raskar.complement(), 0), 0.25}}},
      triplet_row,
      {"three flat 17, averaged", {{ones(17), 1.0 / 3}, {ones(17), 1.0 / 3}, {ones(17), 1.0 / 3}}},
  };
}

/// conv2(image, psf) 'full' along rows: width grows by K - 1, zero outside.
Plane blur_full(const Plane& image, const std::vector<double>& psf) {
  const int k = static_cast<int>(psf.size());
  Plane out(image.width + k - 1, image.height);
  for (int y = 0; y < image.height; ++y)
    for (int n = 0; n < out.width; ++n) {
      double sum = 0;
      for (int j = 0; j < k; ++j) {
        const int x = n - j;
        if (x >= 0 && x < image.width) sum += psf[static_cast<std::size_t>(j)] * image.at(x, y);
      }
      out.at(n, y) = static_cast<float>(sum);
    }
  return out;
}

/// One exposure recorded and deblurred; returns the latent estimate (image size).
Plane expose_and_deblur(const Plane& image, const Exposure& exposure, bool emva,
                        std::mt19937_64& rng) {
  double sum = 0;
  for (double w : exposure.window) sum += w;
  // The PSF normalised to sum 1 (psf / sum(psf)), as the seed's script does.
  std::vector<double> psf;
  for (double w : exposure.window) psf.push_back(w / sum);
  while (!psf.empty() && psf.back() == 0) psf.pop_back();
  const double scale = emva ? kElectrons * exposure.dc : exposure.dc;
  Plane observed = blur_full(image, psf);
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (float& v : observed.pixels) {
    const double signal = v * scale;
    if (emva) {
      const double shot =
          signal > 0 ? static_cast<double>(std::poisson_distribution<long long>(signal)(rng)) : 0.0;
      v = static_cast<float>(shot + kReadNoise * gauss(rng));
    } else {
      const double a = kSeedNoise * exposure.dc;
      v = static_cast<float>(signal + a + a * gauss(rng));
    }
  }
  std::vector<double> taps;
  for (double p : psf) taps.push_back(p * scale);
  const imaging::ChannelPsf channel{taps, 1.0};
  imaging::RichardsonLucy rl({&channel, 1}, observed.width, emva ? kReadNoise * kReadNoise : 0.0,
                             {20, true, 0});
  const Plane full = rl.deconvolve({&observed, 1}, 2);
  Plane latent(image.width, image.height);
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) latent.at(x, y) = full.at(x, y);
  return latent;
}

double row_psnr(const std::vector<Plane>& channels, const Row& row, bool emva, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  double total = 0;
  for (const Plane& channel : channels) {
    Plane mean(channel.width, channel.height);
    for (const Exposure& exposure : row.exposures) {
      const Plane one = expose_and_deblur(channel, exposure, emva, rng);
      for (std::size_t i = 0; i < mean.pixels.size(); ++i)
        mean.pixels[i] += one.pixels[i] / static_cast<float>(row.exposures.size());
    }
    const auto region =
        imaging::scored_region(channel.width, channel.height, kSlots, imaging::Direction::kPlusX);
    total += imaging::psnr(channel, mean, region);
  }
  return total / static_cast<double>(channels.size());
}

}  // namespace

std::vector<SeedExperimentRow> run_seed_experiment(const std::vector<imaging::Plane>& photo,
                                                   std::uint64_t seed) {
  auto spec = sim::parse_scene("code128:FS-0042").value();
  spec.width = 640;
  spec.height = 360;
  const std::vector<Plane> label = {sim::render_scene(spec).value()};
  std::vector<SeedExperimentRow> rows;
  for (const Row& row : seed_rows())
    rows.push_back({row.name, row_psnr(photo, row, false, seed), row_psnr(photo, row, true, seed),
                    row_psnr(label, row, false, seed), row_psnr(label, row, true, seed)});
  return rows;
}

}  // namespace flutterscan::bench
