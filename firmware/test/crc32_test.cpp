#include "flutterscan/firmware/crc32.hpp"

#include <gtest/gtest.h>

#include <array>
#include <string_view>

namespace flutterscan::firmware {
namespace {

std::span<const std::uint8_t> bytes(std::string_view s) {
  return {reinterpret_cast<const std::uint8_t*>(s.data()), s.size()};
}

TEST(Crc32, MatchesTheStandardCheckValue) {
  EXPECT_EQ(crc32(bytes("123456789")), 0xCBF43926u);
  EXPECT_EQ(crc32(bytes("The quick brown fox jumps over the lazy dog")), 0x414FA339u);
}

TEST(Crc32, EmptyInputIsZero) {
  EXPECT_EQ(crc32({}), 0u);
}

TEST(Crc32, ExtendingEqualsOneShot) {
  EXPECT_EQ(crc32_extend(crc32(bytes("12345")), bytes("6789")), 0xCBF43926u);
  EXPECT_EQ(crc32_extend(0, bytes("123456789")), 0xCBF43926u);
}

TEST(Crc32, EverySingleBitFlipChangesIt) {
  std::array<std::uint8_t, 16> data{};
  for (std::size_t i = 0; i < data.size(); ++i) data[i] = static_cast<std::uint8_t>(i * 37);
  const std::uint32_t reference = crc32(data);
  for (std::size_t i = 0; i < data.size(); ++i)
    for (int bit = 0; bit < 8; ++bit) {
      data[i] ^= static_cast<std::uint8_t>(1u << bit);
      EXPECT_NE(crc32(data), reference) << "byte " << i << " bit " << bit;
      data[i] ^= static_cast<std::uint8_t>(1u << bit);
    }
}

}  // namespace
}  // namespace flutterscan::firmware
