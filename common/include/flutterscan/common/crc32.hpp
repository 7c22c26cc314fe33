#pragma once
// CRC-32 as used by zlib, PNG and Ethernet: reflected polynomial 0xEDB88320,
// initial value and final XOR 0xFFFFFFFF. crc32("123456789") == 0xCBF43926.
// Header-only and constexpr so the host, the firmware and the image header
// checker share one implementation. Freestanding.
//
// Byte-at-a-time with a 256-entry table computed at compile time (1 KiB of
// flash on the MCU): eight times fewer steps than the bitwise loop, which
// matters for the config page (2 KiB, CRC-checked on every boot and save)
// and the application image the bootloader checks before every start.

#include <array>
#include <cstdint>
#include <span>

namespace flutterscan {

namespace crc32_detail {

constexpr std::uint32_t kPolynomialReflected = 0xEDB88320u;

/// Entry b: the register after shifting the byte b through the bitwise CRC.
constexpr std::array<std::uint32_t, 256> make_table() {
  std::array<std::uint32_t, 256> table{};
  for (std::uint32_t b = 0; b < 256; ++b) {
    std::uint32_t reg = b;
    for (int bit = 0; bit < 8; ++bit) reg = (reg >> 1) ^ ((reg & 1u) ? kPolynomialReflected : 0u);
    table[b] = reg;
  }
  return table;
}

inline constexpr std::array<std::uint32_t, 256> kTable = make_table();

}  // namespace crc32_detail

/// \brief CRC-32 of the bytes whose CRC-32 is `crc` followed by `data`
/// (crc32_extend(crc32(a), b) == crc32(a + b); crc32_extend(0, a) == crc32(a)).
/// Never inlined at run time: one copy in flash, and the fuzz build's
/// coverage ignorelist (firmware/fuzz/coverage_ignorelist.txt) can leave
/// this byte loop uninstrumented only while it stays a function of its own.
[[gnu::noinline]] constexpr std::uint32_t crc32_extend(std::uint32_t crc,
                                                       std::span<const std::uint8_t> data) {
  std::uint32_t reg = ~crc;
  const std::uint32_t* const table = crc32_detail::kTable.data();
  const std::uint8_t* p = data.data();
  const std::uint8_t* const end = p + data.size();
  for (; p != end; ++p) reg = (reg >> 8) ^ table[(reg ^ *p) & 0xFFu];
  return ~reg;
}

/// \brief CRC-32 of `data`.
constexpr std::uint32_t crc32(std::span<const std::uint8_t> data) {
  return crc32_extend(0, data);
}

}  // namespace flutterscan
