// tv's PSNR against its iteration count on speed_accuracy's label scenes
// (Code 128, EAN-13, QR, Data Matrix, text; 640x360, 2 noise seeds each), per
// light level: how many iterations the solver needs to get close to its
// minimum, the figure kTotalVariationIterations is fixed from.
//
//   tv_iterations [--electrons 300,3000,10000] [--code found-joint] [--edge-prior tv|l0]
//
// Prints a Markdown table: mean PSNR per iteration count, and the largest gap
// of one scene to its own 160-iteration PSNR.

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "bench/capture_schemes.hpp"
#include "codes/library.hpp"
#include "imaging/deblur.hpp"
#include "imaging/frame_conversion.hpp"
#include "imaging/metrics.hpp"
#include "sim/forward_model.hpp"
#include "sim/pixel_integration.hpp"
#include "sim/scene.hpp"

namespace {

using namespace flutterscan;

/// PSNR of tv per scene image (5 scenes x 2 seeds) for each count in `iterations`.
std::vector<std::vector<double>> psnr_per_image(const imaging::CaptureModel& model,
                                                imaging::EdgePrior prior,
                                                const std::vector<int>& iterations) {
  const std::vector<std::string> scenes = {"code128:FS-0042", "ean13:4006381333931",
                                           "qr:FLUTTERSCAN", "datamatrix:LOT-2611", "text:LOT 42"};
  std::vector<std::vector<double>> psnr;
  for (const auto& text : scenes) {
    auto spec = sim::parse_scene(text).value();
    spec.width = 640;
    spec.height = 360;
    const auto fine = sim::render_scene(spec, sim::kSimSupersample).value();
    const auto truth = sim::bin_pixels(fine, sim::kSimSupersample);
    const auto expected = sim::expected_electrons(fine, model, sim::kSimSupersample);
    const auto region = imaging::scored_region(truth.width, truth.height, 52, model.direction);
    for (int seed = 1; seed <= 2; ++seed) {
      const auto electrons = imaging::dn_to_electrons(
          sim::record_frame(expected, model, static_cast<std::uint64_t>(seed)), model);
      std::vector<double> row;
      for (int count : iterations) {
        imaging::DeblurOptions options;
        options.method = imaging::Method::kTotalVariation;
        options.iterations = count;
        options.edge_prior = prior;
        row.push_back(imaging::psnr(
            truth, imaging::deblur(electrons, model, options).value().latent, region));
      }
      psnr.push_back(row);
    }
  }
  return psnr;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<double> levels = {300, 3000, 10000};
  std::string code_name = "found-joint";
  auto prior = imaging::EdgePrior::kTotalVariation;
  for (int i = 1; i < argc; i += 2) {
    const std::string flag = argv[i];
    if (i + 1 == argc) {
      std::fprintf(stderr, "tv_iterations: %s needs a value\n", flag.c_str());
      return 2;
    }
    const std::string value = argv[i + 1];
    if (flag == "--electrons") {
      levels.clear();
      std::stringstream list(value);
      for (std::string item; std::getline(list, item, ',');) {
        char* end = nullptr;
        const double electrons = std::strtod(item.c_str(), &end);
        if (item.empty() || *end != '\0' || !(electrons > 0)) {
          std::fprintf(stderr, "tv_iterations: --electrons: '%s' is not a number > 0\n",
                       item.c_str());
          return 2;
        }
        levels.push_back(electrons);
      }
    } else if (flag == "--code") {
      code_name = value;
    } else if (flag == "--edge-prior" && (value == "tv" || value == "l0")) {
      prior = value == "l0" ? imaging::EdgePrior::kL0Gradient : imaging::EdgePrior::kTotalVariation;
    } else {
      std::fprintf(stderr, "tv_iterations: unknown option %s %s\n", flag.c_str(), value.c_str());
      return 2;
    }
  }
  const auto code = codes::find_library_code(code_name);
  if (!code) {
    std::fprintf(stderr, "tv_iterations: no library code named '%s'\n", code_name.c_str());
    return 2;
  }
  const std::vector<int> iterations = {5, 10, 15, 20, 40, 80, 160};
  std::printf(
      "%s, %s, cap 3, read noise 4 e-, 52 px blur: mean PSNR (dB) over 5 label scenes x 2 "
      "seeds; worst: the largest gap of one image to its 160-iteration PSNR\n\n",
      code_name.c_str(), prior == imaging::EdgePrior::kL0Gradient ? "L0" : "TV");
  std::printf("| e- |");
  for (int count : iterations) std::printf(" %d |", count);
  std::printf(" worst at %d |\n|---|", imaging::kTotalVariationIterations);
  for (std::size_t k = 0; k <= iterations.size(); ++k) std::printf("---|");
  std::printf("\n");
  const bench::CaptureScheme scheme{code_name, codes::to_code(*code), true};
  const auto standard = static_cast<std::size_t>(
      std::find(iterations.begin(), iterations.end(), imaging::kTotalVariationIterations) -
      iterations.begin());
  for (double electrons : levels) {
    const auto psnr =
        psnr_per_image(bench::bench_camera(scheme, electrons, 3, 4, 52), prior, iterations);
    std::printf("| %.0f |", electrons);
    for (std::size_t k = 0; k < iterations.size(); ++k) {
      double sum = 0;
      for (const auto& image : psnr) sum += image[k];
      std::printf(" %.2f |", sum / static_cast<double>(psnr.size()));
    }
    double worst = 0;
    if (standard < iterations.size())
      for (const auto& image : psnr) worst = std::max(worst, image.back() - image[standard]);
    std::printf(" %.2f |\n", worst);
    std::fflush(stdout);
  }
}
