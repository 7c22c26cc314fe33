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

// The table-driven implementation against the definition (bit by bit,
// reflected 0xEDB88320), over every byte value at every position mod 4 and
// lengths 0..300, extending across every split point.
std::uint32_t bitwise_crc32(std::span<const std::uint8_t> data) {
  std::uint32_t reg = 0xFFFFFFFFu;
  for (const std::uint8_t byte : data) {
    reg ^= byte;
    for (int bit = 0; bit < 8; ++bit) reg = (reg >> 1) ^ ((reg & 1u) ? 0xEDB88320u : 0u);
  }
  return ~reg;
}

TEST(Crc32, TableDrivenEqualsBitwiseDefinition) {
  std::array<std::uint8_t, 300> data{};
  std::uint32_t x = 12345;
  for (auto& b : data) {
    x = x * 1103515245u + 12345u;
    b = static_cast<std::uint8_t>(x >> 16);
  }
  for (std::size_t n = 0; n <= data.size(); ++n) {
    const auto part = std::span<const std::uint8_t>(data).first(n);
    ASSERT_EQ(crc32(part), bitwise_crc32(part)) << "length " << n;
  }
  for (int value = 0; value < 256; ++value) {
    const std::array<std::uint8_t, 4> one{static_cast<std::uint8_t>(value), 0x5A,
                                          static_cast<std::uint8_t>(~value), 0x00};
    ASSERT_EQ(crc32(one), bitwise_crc32(one)) << "byte " << value;
  }
  const auto all = std::span<const std::uint8_t>(data).first(64);
  for (std::size_t split = 0; split <= all.size(); ++split)
    ASSERT_EQ(crc32_extend(crc32(all.first(split)), all.subspan(split)), bitwise_crc32(all));
}

static_assert(crc32(std::span<const std::uint8_t>()) == 0u);

}  // namespace
}  // namespace flutterscan::firmware
