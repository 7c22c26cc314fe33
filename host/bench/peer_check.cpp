// The peer check of docs/benchmarks.md ("A peer simulator's physics"): real
// label photographs (../shared/data/real-labels, skipped cleanly where absent)
// captured by a numerical flutter shutter that this project's simulator and
// PSF code play no part in, the way the IPOL flutter-shutter simulator
// (Tendero 2012) models it: a mono camera, Raskar's 52-slot code, one pixel of
// motion per slot, the scene band-limited (Shannon) and moving continuously
// while the shutter is open, noise at SNR 100 (sigma = mean / 100), 8-bit
// output. Per photo, PSNR (peak 255) over the interior (52 px borders
// excluded along the motion) of:
// - the peer's own reconstruction, the exact inverse filter of its float data;
// - the same inverse filter on the 8-bit output (what 8 bits leave);
// - `imaging::deblur` (joint Wiener and tv) on the 8-bit output, told the
//   capture as a descriptor would tell it: with the default pixel model (box
//   aperture) and with pixel_model "band-limited" (the peer's).
// Usage: peer_check [PHOTO_DIR [SNR]] (default ../shared/data/real-labels, 100).
// The renderer: each row's DFT times the continuous code's transform,
// K(w) = (1 / n) sum over open slots t of sinc(w / 2 pi) exp(-i w (t + 1/2)),
// periodic along the row (cv::dft; the borders are not scored).

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "bench/cpu_model.hpp"
#include "codes/library.hpp"
#include "imaging/capture_model.hpp"
#include "imaging/deblur.hpp"
#include "imaging/image.hpp"

namespace {

using namespace flutterscan;
namespace fs = std::filesystem;

constexpr int kBorder = 52;
constexpr double kPi = 3.14159265358979323846;

/// The continuous code's transform at w (radians per pixel): the open slots'
/// one-pixel boxes, band-limited, normalised to 1 at w = 0.
std::complex<double> code_transform(const std::string& bits, double w) {
  const double sinc = w == 0 ? 1.0 : std::sin(w / 2) / (w / 2);
  std::complex<double> sum = 0;
  int open = 0;
  for (std::size_t t = 0; t < bits.size(); ++t)
    if (bits[t] == '1') {
      sum += std::polar(1.0, -w * (static_cast<double>(t) + 0.5));
      ++open;
    }
  return sum * sinc / static_cast<double>(open);
}

/// Radians per pixel of DFT bin k of a length-n row (negative above n / 2).
double bin_frequency(int k, int n) {
  return 2 * kPi * (k <= n / 2 ? k : k - n) / n;
}

/// Each row of `rows` (CV_64F) multiplied in frequency by `filter(w)`, or
/// divided by it when `inverse`.
cv::Mat filter_rows(const cv::Mat& rows, const std::string& bits, bool inverse) {
  cv::Mat spectrum;
  cv::dft(rows, spectrum, cv::DFT_ROWS | cv::DFT_COMPLEX_OUTPUT);
  const int n = rows.cols;
  std::vector<std::complex<double>> gain(static_cast<std::size_t>(n));
  for (int k = 0; k < n; ++k) {
    const auto g = code_transform(bits, bin_frequency(k, n));
    gain[static_cast<std::size_t>(k)] = inverse ? 1.0 / g : g;
  }
  for (int y = 0; y < spectrum.rows; ++y) {
    auto* row = spectrum.ptr<std::complex<double>>(y);
    for (int k = 0; k < n; ++k) row[k] *= gain[static_cast<std::size_t>(k)];
  }
  cv::Mat out;
  cv::dft(spectrum, out, cv::DFT_ROWS | cv::DFT_INVERSE | cv::DFT_SCALE | cv::DFT_REAL_OUTPUT);
  return out;
}

double interior_psnr(const cv::Mat& truth, const cv::Mat& estimate) {
  double sum = 0;
  long count = 0;
  for (int y = 0; y < truth.rows; ++y)
    for (int x = kBorder; x < truth.cols - kBorder; ++x) {
      const double d = truth.at<double>(y, x) - estimate.at<double>(y, x);
      sum += d * d;
      ++count;
    }
  return 10 * std::log10(255.0 * 255.0 / (sum / static_cast<double>(count)));
}

/// The capture as a descriptor tells it to flutterscan: mono, Raskar's code on
/// one LED, 52 px along +x, 8 bits, a noise of `sigma_dn` DN (read noise; the
/// gain so high that shot noise is a tenth of it), reflectance 1 = 255 DN.
imaging::CaptureModel told_model(const LedCode& code, double sigma_dn) {
  imaging::CaptureModel m;
  m.code = code;
  m.blur_px = 52;
  m.channels = 1;
  m.leds = 1;
  m.crosstalk = {1};
  m.ambient_electrons = {0};
  m.gain = 10000;
  m.bit_depth = 8;
  m.full_well = 256 * m.gain;
  m.read_noise = sigma_dn * m.gain;
  m.led_electrons = {255 * m.gain / code.on_slots(0)};
  return m;
}

struct Scores {
  double peer_float = 0, inverse_8bit = 0;
  double box_wiener = 0, box_tv = 0;    ///< the default pixel model (box aperture)
  double band_wiener = 0, band_tv = 0;  ///< told pixel_model "band-limited"
};

Scores check(const cv::Mat& scene, const std::string& bits, const LedCode& code, double snr,
             std::uint64_t seed) {
  Scores s;
  const cv::Mat clean = filter_rows(scene, bits, false);
  const double sigma = cv::mean(clean)[0] / snr;
  cv::Mat noisy = clean.clone();
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0, sigma);
  for (int y = 0; y < noisy.rows; ++y)
    for (int x = 0; x < noisy.cols; ++x) noisy.at<double>(y, x) += noise(rng);
  s.peer_float = interior_psnr(scene, filter_rows(noisy, bits, true));
  cv::Mat eight = noisy.clone();
  for (int y = 0; y < eight.rows; ++y)
    for (int x = 0; x < eight.cols; ++x)
      eight.at<double>(y, x) = std::clamp(std::round(eight.at<double>(y, x)), 0.0, 255.0);
  s.inverse_8bit = interior_psnr(scene, filter_rows(eight, bits, true));

  auto model = told_model(code, std::sqrt(sigma * sigma + 1.0 / 12));
  imaging::Image electrons;
  electrons.channels.assign(1, imaging::Plane(eight.cols, eight.rows));
  for (int y = 0; y < eight.rows; ++y)
    for (int x = 0; x < eight.cols; ++x)
      electrons.channels[0].at(x, y) = static_cast<float>(eight.at<double>(y, x) * model.gain);
  for (const auto pixels : {imaging::PixelModel::kBoxAperture, imaging::PixelModel::kBandLimited})
    for (const auto method : {imaging::Method::kJointWiener, imaging::Method::kTotalVariation}) {
      model.pixel_model = pixels;
      imaging::DeblurOptions options;
      options.method = method;
      options.threads = 2;
      const auto r = imaging::deblur(electrons, model, options);
      if (!r.ok()) {
        std::fprintf(stderr, "deblur failed: %s\n", r.error().c_str());
        continue;
      }
      cv::Mat latent(eight.rows, eight.cols, CV_64F);
      for (int y = 0; y < eight.rows; ++y)
        for (int x = 0; x < eight.cols; ++x)
          latent.at<double>(y, x) = 255.0 * r.value().latent.at(x, y);
      const bool box = pixels == imaging::PixelModel::kBoxAperture;
      const bool wiener = method == imaging::Method::kJointWiener;
      (box ? (wiener ? s.box_wiener : s.box_tv) : (wiener ? s.band_wiener : s.band_tv)) =
          interior_psnr(scene, latent);
    }
  return s;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  const fs::path photos = argc > 1 ? argv[1] : "../shared/data/real-labels";
  const double snr = argc > 2 ? std::atof(argv[2]) : 100;
  if (!fs::is_directory(photos)) {
    std::printf("peer check: %s not found (the shared label photos): skipped\n",
                photos.string().c_str());
    return 0;
  }
  const auto entry = codes::find_library_code("raskar");
  const LedCode code = codes::to_code(*entry);
  const std::string bits(entry->digits);
  std::vector<fs::path> files;
  for (const auto& f : fs::directory_iterator(photos))
    if (f.path().extension() == ".png" || f.path().extension() == ".jpg") files.push_back(f.path());
  std::sort(files.begin(), files.end());
  std::printf(
      "CPU: %s\n\npeer check: %zu photos as band-limited scenes, Raskar's code, 52 px "
      "(one per slot), SNR %.0f, 8-bit; PSNR dB over the interior (%d px borders "
      "excluded)\n\n| photo | peer, float | inverse filter, 8-bit | joint Wiener | tv | joint "
      "Wiener, band-limited | tv, band-limited |\n|---|---|---|---|---|---|---|\n",
      bench::cpu_model().c_str(), files.size(), snr, kBorder);
  std::vector<std::vector<double>> columns(6);
  std::uint64_t seed = 1;
  for (const auto& path : files) {
    cv::Mat grey = cv::imread(path.string(), cv::IMREAD_GRAYSCALE);
    if (grey.empty() || grey.cols < 4 * kBorder) continue;
    cv::Mat scene;
    grey.convertTo(scene, CV_64F);
    const auto s = check(scene, bits, code, snr, seed++);
    const double row[] = {s.peer_float, s.inverse_8bit, s.box_wiener,
                          s.box_tv,     s.band_wiener,  s.band_tv};
    std::printf("| %s |", path.filename().string().c_str());
    for (std::size_t i = 0; i < columns.size(); ++i) {
      std::printf(" %.1f |", row[i]);
      columns[i].push_back(row[i]);
    }
    std::printf("\n");
  }
  std::printf("| **median** |");
  for (const auto& column : columns) std::printf(" **%.1f** |", median(column));
  std::printf("\n");
  return 0;
}
