#include "codes/incremental_spectra.hpp"

#include <numbers>

namespace flutterscan::codes {

IncrementalSpectra::IncrementalSpectra(const LedCode& code, std::vector<double> frequency)
    : code_(code) {
  spectra_.leds = code.leds();
  spectra_.length = code.length();
  spectra_.frequency = std::move(frequency);
  const std::size_t points = spectra_.frequency.size();
  twiddles_.resize(points * static_cast<std::size_t>(code.length()));
  for (int t = 0; t < code.length(); ++t)
    for (std::size_t j = 0; j < points; ++j)
      twiddles_[static_cast<std::size_t>(t) * points + j] =
          std::polar(1.0, -2.0 * std::numbers::pi * spectra_.frequency[j] * t);
  spectra_.h.assign(points * static_cast<std::size_t>(code.leds()), {});
  refresh();
}

void IncrementalSpectra::refresh() {
  const std::size_t points = spectra_.frequency.size();
  std::fill(spectra_.h.begin(), spectra_.h.end(), std::complex<double>{});
  spectra_.on_slots.fill(0);
  for (int t = 0; t < code_.length(); ++t) {
    const auto* tw = twiddles(t);
    for (int k = 0; k < code_.leds(); ++k) {
      if (!code_.is_on(t, k)) continue;
      ++spectra_.on_slots[static_cast<std::size_t>(k)];
      auto* h = spectra_.h.data() + static_cast<std::size_t>(k) * points;
      for (std::size_t j = 0; j < points; ++j) h[j] += tw[j];
    }
  }
}

void IncrementalSpectra::set_mask(int slot, std::uint8_t mask) {
  const std::uint8_t changed = code_.mask(slot) ^ mask;
  const std::size_t points = spectra_.frequency.size();
  const auto* tw = twiddles(slot);
  for (int k = 0; k < code_.leds(); ++k) {
    if (((changed >> k) & 1U) == 0) continue;
    auto* h = spectra_.h.data() + static_cast<std::size_t>(k) * points;
    if ((mask >> k) & 1U) {
      for (std::size_t j = 0; j < points; ++j) h[j] += tw[j];
      ++spectra_.on_slots[static_cast<std::size_t>(k)];
    } else {
      for (std::size_t j = 0; j < points; ++j) h[j] -= tw[j];
      --spectra_.on_slots[static_cast<std::size_t>(k)];
    }
  }
  code_.set_mask(slot, mask);
}

}  // namespace flutterscan::codes
