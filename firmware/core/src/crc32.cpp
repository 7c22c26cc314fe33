#include "flutterscan/firmware/crc32.hpp"

namespace flutterscan::firmware {
namespace {

constexpr std::uint32_t kPolynomialReflected = 0xEDB88320u;

}  // namespace

std::uint32_t crc32_extend(std::uint32_t crc, std::span<const std::uint8_t> data) {
  std::uint32_t reg = ~crc;
  for (const std::uint8_t byte : data) {
    reg ^= byte;
    for (int bit = 0; bit < 8; ++bit) reg = (reg >> 1) ^ ((reg & 1u) ? kPolynomialReflected : 0u);
  }
  return ~reg;
}

std::uint32_t crc32(std::span<const std::uint8_t> data) {
  return crc32_extend(0, data);
}

}  // namespace flutterscan::firmware
