#pragma once
// The seed's Section 6 / Appendix A experiment, rerun: flat 52, Raskar,
// Raskar + inverted averaged, the triplet averaged (the seed's duty factors
// 16/52, 18/52, 18/52 are those of its avg-min code), three short flat-17
// exposures averaged; each deblurred by Richardson-Lucy with 20 iterations
// (deconvlucy's default Biggs-Andrews acceleration), per channel, as the seed
// did. Once under the seed's noise model (Gaussian noise with mean and
// standard deviation 0.01 x the duty factor, which makes the SNR independent
// of the light collected) and once under the EMVA 1288 model at one light
// budget (3000 e- for a white object over the whole exposure through the
// same shutter, Poisson shot noise, 4 e- read noise).

#include <cstdint>
#include <string>
#include <vector>

#include "imaging/image.hpp"

namespace flutterscan::bench {

struct SeedExperimentRow {
  std::string name;
  double photo_seed_noise, photo_emva;  ///< PSNR (dB) on the photograph
  double label_seed_noise, label_emva;  ///< PSNR (dB) on a rendered Code 128 label
};

/// \brief Runs every row on `photo` (planes with values in [0, 1], the stored
/// values as MATLAB's im2double reads them) and on a rendered label.
std::vector<SeedExperimentRow> run_seed_experiment(const std::vector<imaging::Plane>& photo,
                                                   std::uint64_t seed);

}  // namespace flutterscan::bench
