#pragma once
// Spectra of LED sequences: the seed's 64-point grid, the dense grid of the
// continuous spectrum a linear blur sees, and the circular L-point spectrum a
// cyclically repeated pattern sees. Frequencies are in cycles per slot, 0..0.5.

#include <complex>
#include <span>
#include <vector>

#include "flutterscan/common/led_code.hpp"

namespace flutterscan::codes {

/// \brief 0/1 samples of one LED's on-slots (slot 0 first).
std::vector<double> led_sequence(const LedCode& code, int led);

/// \brief The seed's FFT size for a code of `length` slots: the first power of two above it.
int seed_grid_size(int length);

/// \brief The seed's dB scale: 20 log10(|F| / (N/2)), N = seed_grid_size(length).
/// Magnitudes below kNullMagnitude count as an exact null and map to kNullDb.
double seed_db(double magnitude, int length);
inline constexpr double kNullMagnitude = 1e-12;
inline constexpr double kNullDb = -240.0;

/// \brief The DTFT of `sequence` at frequency `f` (cycles per slot).
std::complex<double> dtft(std::span<const double> sequence, double f);

/// \brief The DFT of `sequence` zero-padded to `size` points, bins 0..size/2
/// (frequency of bin j is j / size). Uses FFTW.
std::vector<std::complex<double>> padded_dft(std::span<const double> sequence, int size);

/// \brief A spectrum sampled on a grid, in the seed's dB.
struct SampledSpectrum {
  std::vector<double> frequency;  ///< cycles per slot
  std::vector<double> db;
};

/// \brief The seed's grid: zero-pad to seed_grid_size, bins 0..N/2.
SampledSpectrum seed_grid_spectrum(std::span<const double> sequence);

/// \brief The circular L-point DFT (bins 0..L/2), in the seed's dB.
SampledSpectrum circular_spectrum(std::span<const double> sequence);

/// \brief A dense grid of the continuous (linear-blur) spectrum with `points` bins over 0..0.5.
SampledSpectrum dense_spectrum(std::span<const double> sequence, int points = 4096);

/// \brief Where a function of frequency is smallest, on a grid and after local refinement.
struct Minimum {
  double grid_value = 0;
  double grid_frequency = 0;
  double refined_value = 0;
  double refined_frequency = 0;
};

/// \brief Minimises `value_at(f)` over 0..0.5: first on the grid `samples`
/// (values at frequencies j * 0.5 / (samples.size() - 1)), then refines the
/// lowest few local minima by golden-section search within one grid step.
template <typename ValueAt>
Minimum minimise_over_frequency(std::span<const double> samples, ValueAt value_at);

/// \brief Grid and refined minimum of a sequence's linear-blur spectrum, in the seed's dB.
Minimum dense_minimum_db(std::span<const double> sequence, int points = 4096);

}  // namespace flutterscan::codes

#include "codes/minimise_over_frequency.ipp"
