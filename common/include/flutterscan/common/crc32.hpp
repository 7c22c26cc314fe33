#pragma once
// CRC-32 as used by zlib, PNG and Ethernet: reflected polynomial 0xEDB88320,
// initial value and final XOR 0xFFFFFFFF. crc32("123456789") == 0xCBF43926.
// Header-only and constexpr so the host, the firmware and the image header
// checker share one implementation. Freestanding.

#include <cstdint>
#include <span>

namespace flutterscan {

/// \brief CRC-32 of the bytes whose CRC-32 is `crc` followed by `data`
/// (crc32_extend(crc32(a), b) == crc32(a + b); crc32_extend(0, a) == crc32(a)).
constexpr std::uint32_t crc32_extend(std::uint32_t crc, std::span<const std::uint8_t> data) {
  constexpr std::uint32_t kPolynomialReflected = 0xEDB88320u;
  std::uint32_t reg = ~crc;
  for (const std::uint8_t byte : data) {
    reg ^= byte;
    for (int bit = 0; bit < 8; ++bit) reg = (reg >> 1) ^ ((reg & 1u) ? kPolynomialReflected : 0u);
  }
  return ~reg;
}

/// \brief CRC-32 of `data`.
constexpr std::uint32_t crc32(std::span<const std::uint8_t> data) {
  return crc32_extend(0, data);
}

}  // namespace flutterscan
