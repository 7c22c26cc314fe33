#pragma once
// CRC-32 as used by zlib, PNG and Ethernet: reflected polynomial 0xEDB88320,
// initial value and final XOR 0xFFFFFFFF. crc32("123456789") == 0xCBF43926.

#include <cstdint>
#include <span>

namespace flutterscan::firmware {

/// \brief CRC-32 of `data`.
std::uint32_t crc32(std::span<const std::uint8_t> data);

/// \brief CRC-32 of the bytes whose CRC-32 is `crc` followed by `data`
/// (crc32_extend(crc32(a), b) == crc32(a + b); crc32_extend(0, a) == crc32(a)).
std::uint32_t crc32_extend(std::uint32_t crc, std::span<const std::uint8_t> data);

}  // namespace flutterscan::firmware
