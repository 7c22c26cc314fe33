#pragma once
// Per-LED spectra of a code on a fixed frequency grid, updated in O(grid) when
// one slot changes: slot t contributes exp(-2 pi i f t) to every LED lit in it.

#include <complex>
#include <vector>

#include "codes/merits.hpp"

namespace flutterscan::codes {

class IncrementalSpectra {
 public:
  /// \brief Spectra of `code` at `frequency` (cycles per slot).
  IncrementalSpectra(const LedCode& code, std::vector<double> frequency);

  /// \brief Changes one slot's mask and updates the LEDs it turns on or off.
  void set_mask(int slot, std::uint8_t mask);
  /// \brief Recomputes every spectrum from the code, clearing accumulated rounding.
  void refresh();
  /// \brief Replaces the whole code (same LEDs and length) and recomputes, in O(slots x grid).
  void assign(const LedCode& code) {
    code_ = code;
    refresh();
  }

  const LedCode& code() const { return code_; }
  const GridSpectra& spectra() const { return spectra_; }

 private:
  const std::complex<double>* twiddles(int slot) const {
    return twiddles_.data() + static_cast<std::size_t>(slot) * spectra_.frequency.size();
  }
  LedCode code_;
  GridSpectra spectra_;
  std::vector<std::complex<double>> twiddles_;  ///< exp(-2 pi i f_j t), by slot t
};

}  // namespace flutterscan::codes
