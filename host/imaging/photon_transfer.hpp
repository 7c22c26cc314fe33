#pragma once
// `calibrate noise`: conversion gain (e-/DN) and read noise (e-) from a photon
// transfer measurement in the manner of EMVA 1288: pairs of flat frames (same
// light, taken one after the other) at several light levels, and a pair with
// no light. For each pair and channel, the mean signal above dark is
// mu = mean((A + B) / 2) - mu_dark and the temporal variance is
// var(A - B) / 2 (differencing removes fixed-pattern noise). Shot noise makes
// var - var_dark = K * mu with K = 1 / gain, fitted by least squares through
// the origin over the levels below 70% of the saturation range (EMVA 1288's
// fit range). Read noise = sqrt(var_dark - 1/12) / K (the 1/12 DN^2 is the
// quantisation noise).

#include <span>
#include <string>
#include <vector>

#include "flutterscan/common/result.hpp"
#include "imaging/image.hpp"

namespace flutterscan::imaging {

/// \brief Two frames at one light level.
struct FlatPair {
  Image first, second;
};

/// \brief One point of the photon transfer curve of one channel.
struct TransferPoint {
  double mean_dn = 0;       ///< above dark
  double variance_dn2 = 0;  ///< temporal, dark variance included
  bool fitted = false;      ///< inside the fit range
};

struct PhotonTransfer {
  std::vector<double> gain_e_per_dn;               ///< per channel
  std::vector<double> read_noise_e;                ///< per channel
  std::vector<double> black_level_dn;              ///< per channel
  std::vector<std::vector<TransferPoint>> points;  ///< per channel, one per flat pair
};

/// \brief Fits the photon transfer of every channel. `full_scale_dn` is the
/// largest DN (2^bits - 1). Fails naming the pair that does not match, or when
/// fewer than two levels fall inside the fit range.
Result<PhotonTransfer, std::string> photon_transfer(const FlatPair& dark,
                                                    std::span<const FlatPair> flats,
                                                    double full_scale_dn);

}  // namespace flutterscan::imaging
