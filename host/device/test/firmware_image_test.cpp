// Image loading: .bin, .hex and .elf give the same bytes; wrong board, corrupt
// and truncated images are refused with the reason.
#include "device/firmware_image.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>

namespace flutterscan::device {
namespace {

namespace fs = std::filesystem;
using Bytes = std::vector<std::uint8_t>;

constexpr AppRegion kRegion = kStm32f405AppRegion;

/// A stamped image: header, zero padding to 512, then `payload_size` pattern bytes
/// with a zero run in the middle (a gap in .hex/.elf form).
Bytes make_image(std::uint16_t board_id, std::size_t payload_size = 3000) {
  Bytes image(512 + payload_size, 0);
  ImageHeader header{};
  header.magic = kImageMagic;
  header.header_version = kImageHeaderVersion;
  header.header_size = sizeof(ImageHeader);
  header.board_id = board_id;
  header.version_major = 0;
  header.version_minor = 1;
  header.version_patch = 0;
  header.load_address = kRegion.load_address;
  header.vector_table_offset = 512;
  std::memcpy(image.data(), &header, sizeof header);
  for (std::size_t i = 512; i < image.size(); ++i)
    image[i] = (i > 1500 && i < 1700) ? 0 : static_cast<std::uint8_t>(i * 7 + 3);
  EXPECT_TRUE(stamp_image(image));
  return image;
}

/// The folder of this process's image files under the temp directory.
fs::path temp_folder() {
  return fs::temp_directory_path() / ("flutterscan_image_test_" + std::to_string(::getpid()));
}

fs::path temp_file(const std::string& name) {
  fs::create_directories(temp_folder());
  return temp_folder() / name;
}

/// Removes the image files once every test has run.
class TempFolderCleanup : public ::testing::Environment {
 public:
  void TearDown() override {
    std::error_code ignored;
    fs::remove_all(temp_folder(), ignored);
  }
};
[[maybe_unused]] ::testing::Environment* const kTempFolderCleanup =
    ::testing::AddGlobalTestEnvironment(new TempFolderCleanup);

void write_file(const fs::path& path, const Bytes& bytes) {
  std::ofstream(path, std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()),
             static_cast<std::streamsize>(bytes.size()));
}

void write_text(const fs::path& path, const std::string& text) {
  std::ofstream(path) << text;
}

std::string hex_record(std::uint8_t type, std::uint16_t address, const std::uint8_t* data,
                       std::size_t length) {
  std::string line = ":";
  char byte_text[4];
  unsigned sum = static_cast<unsigned>(length) + (address >> 8) + (address & 0xFF) + type;
  std::snprintf(byte_text, sizeof byte_text, "%02X", static_cast<unsigned>(length));
  line += byte_text;
  std::snprintf(byte_text, sizeof byte_text, "%02X", address >> 8);
  line += byte_text;
  std::snprintf(byte_text, sizeof byte_text, "%02X", address & 0xFF);
  line += byte_text;
  std::snprintf(byte_text, sizeof byte_text, "%02X", type);
  line += byte_text;
  for (std::size_t i = 0; i < length; ++i) {
    std::snprintf(byte_text, sizeof byte_text, "%02X", data[i]);
    line += byte_text;
    sum += data[i];
  }
  std::snprintf(byte_text, sizeof byte_text, "%02X", (256 - (sum & 0xFF)) & 0xFF);
  return line + byte_text + "\n";
}

/// Intel HEX of `image` at `address`, skipping all-zero 16-byte rows (as a linker leaves gaps).
std::string to_hex(const Bytes& image, std::uint32_t address) {
  std::string text;
  std::uint32_t upper = 0xFFFFFFFF;
  for (std::size_t at = 0; at < image.size(); at += 16) {
    const std::size_t length = std::min<std::size_t>(16, image.size() - at);
    bool all_zero = true;
    for (std::size_t i = 0; i < length; ++i) all_zero &= image[at + i] == 0;
    if (all_zero && at + length < image.size()) continue;
    const std::uint32_t target = address + static_cast<std::uint32_t>(at);
    if ((target >> 16) != upper) {
      upper = target >> 16;
      const std::uint8_t base[2] = {static_cast<std::uint8_t>(upper >> 8),
                                    static_cast<std::uint8_t>(upper)};
      text += hex_record(0x04, 0, base, 2);
    }
    text +=
        hex_record(0x00, static_cast<std::uint16_t>(target & 0xFFFF), image.data() + at, length);
  }
  return text + ":00000001FF\n";
}

void put32(Bytes& out, std::size_t at, std::uint32_t value) {
  for (int i = 0; i < 4; ++i) out[at + i] = static_cast<std::uint8_t>(value >> (8 * i));
}
void put16(Bytes& out, std::size_t at, std::uint16_t value) {
  out[at] = static_cast<std::uint8_t>(value);
  out[at + 1] = static_cast<std::uint8_t>(value >> 8);
}

/// A minimal ELF32 ARM executable: `image` split into two PT_LOAD segments at
/// `address` (the second skipping the zero run), plus a .bss-like empty segment.
Bytes to_elf(const Bytes& image, std::uint32_t address, std::uint16_t machine = 40) {
  const std::size_t split = 1600;
  const std::size_t second = 1700;
  const std::size_t headers = 52 + 3 * 32;
  Bytes elf(headers, 0);
  elf[0] = 0x7F, elf[1] = 'E', elf[2] = 'L', elf[3] = 'F', elf[4] = 1, elf[5] = 1, elf[6] = 1;
  put16(elf, 16, 2);  // ET_EXEC
  put16(elf, 18, machine);
  put32(elf, 20, 1);
  put32(elf, 24, address + 513);
  put32(elf, 28, 52);
  put16(elf, 40, 52);
  put16(elf, 42, 32);
  put16(elf, 44, 3);
  auto segment = [&](int index, std::uint32_t offset, std::uint32_t paddr, std::uint32_t vaddr,
                     std::uint32_t size, std::uint32_t memsize) {
    const std::size_t at = 52 + static_cast<std::size_t>(index) * 32;
    put32(elf, at, 1);  // PT_LOAD
    put32(elf, at + 4, offset);
    put32(elf, at + 8, vaddr);
    put32(elf, at + 12, paddr);
    put32(elf, at + 16, size);
    put32(elf, at + 20, memsize);
  };
  segment(0, static_cast<std::uint32_t>(headers), address, address, split, split);
  segment(1, static_cast<std::uint32_t>(headers + split), address + second, 0x20000000,
          static_cast<std::uint32_t>(image.size() - second),
          static_cast<std::uint32_t>(image.size() - second));
  segment(2, 0, address + static_cast<std::uint32_t>(image.size()), 0x20001000, 0, 0x400);
  // Copied in place (GCC 12 warns falsely about vector::insert here).
  elf.resize(headers + split + (image.size() - second));
  std::copy(image.begin(), image.begin() + split,
            elf.begin() + static_cast<std::ptrdiff_t>(headers));
  std::copy(image.begin() + second, image.end(),
            elf.begin() + static_cast<std::ptrdiff_t>(headers + split));
  return elf;
}

void expect_refused(const Expected<FirmwareImage>& loaded, const std::string& text) {
  ASSERT_FALSE(loaded.ok());
  EXPECT_EQ(loaded.error().kind, ErrorKind::kBadInput);
  EXPECT_NE(loaded.error().message.find(text), std::string::npos) << loaded.error().message;
}

TEST(FirmwareImage, BinHexAndElfRoundTripToTheSameBytes) {
  const Bytes image = make_image(kBoardIdStm32f405);
  const fs::path bin = temp_file("app.bin");
  const fs::path hex = temp_file("app.hex");
  const fs::path elf = temp_file("app.elf");
  write_file(bin, image);
  write_text(hex, to_hex(image, kRegion.load_address));
  write_file(elf, to_elf(image, kRegion.load_address));
  for (const auto& path : {bin, hex, elf}) {
    const auto loaded = load_firmware_image(path, kRegion);
    ASSERT_TRUE(loaded.ok()) << path << ": " << loaded.error().message;
    EXPECT_EQ(loaded.value().bytes, image) << path;
    EXPECT_EQ(loaded.value().header.board_id, kBoardIdStm32f405);
  }
}

TEST(FirmwareImage, FormatFromContentBeforeExtension) {
  const Bytes elf = to_elf(make_image(kBoardIdStm32f405), kRegion.load_address);
  EXPECT_EQ(guess_image_format("firmware.bin", elf), ImageFormat::kElf);
  const std::string hex = ":00000001FF\n";
  EXPECT_EQ(guess_image_format("firmware", Bytes(hex.begin(), hex.end())), ImageFormat::kIntelHex);
  EXPECT_EQ(guess_image_format("firmware.bin", Bytes{0x46, 0x53}), ImageFormat::kBinary);
}

TEST(FirmwareImage, AnotherBoardsImageIsRefused) {
  const fs::path bin = temp_file("other_board.bin");
  write_file(bin, make_image(kBoardIdQemuNetduinoplus2));
  expect_refused(load_firmware_image(bin, kRegion), "built for another board (image board id 2");
}

TEST(FirmwareImage, ImageLinkedElsewhereIsRefusedNamingTheAddress) {
  const Bytes image = make_image(kBoardIdStm32f405);
  const fs::path hex = temp_file("elsewhere.hex");
  write_text(hex, to_hex(image, 0x08000000));
  expect_refused(load_firmware_image(hex, kRegion), "outside the application region 0x08008000");
}

TEST(FirmwareImage, CorruptImageIsRefused) {
  Bytes image = make_image(kBoardIdStm32f405);
  image[2000] ^= 0x01;
  const fs::path bin = temp_file("corrupt.bin");
  write_file(bin, image);
  expect_refused(load_firmware_image(bin, kRegion), "image CRC-32 does not match");
  Bytes header_hit = make_image(kBoardIdStm32f405);
  header_hit[10] ^= 0x01;  // firmware version byte: header CRC
  write_file(bin, header_hit);
  expect_refused(load_firmware_image(bin, kRegion), "header corrupt");
  write_file(bin, Bytes(4096, 0xAB));
  expect_refused(load_firmware_image(bin, kRegion), "no flutterscan application header");
}

TEST(FirmwareImage, TruncatedFilesAreRefused) {
  const Bytes image = make_image(kBoardIdStm32f405);
  const fs::path bin = temp_file("short.bin");
  write_file(bin, Bytes(image.begin(), image.begin() + 1000));
  expect_refused(load_firmware_image(bin, kRegion), "truncated");

  std::string hex = to_hex(image, kRegion.load_address);
  hex.resize(hex.rfind(":00000001FF"));
  const fs::path hex_path = temp_file("short.hex");
  write_text(hex_path, hex);
  expect_refused(load_firmware_image(hex_path, kRegion), "no end-of-file record");

  const Bytes elf = to_elf(image, kRegion.load_address);
  const fs::path elf_path = temp_file("short.elf");
  write_file(elf_path, Bytes(elf.begin(), elf.end() - 100));
  expect_refused(load_firmware_image(elf_path, kRegion), "segment 1 runs past the end");
  write_file(elf_path, Bytes(elf.begin(), elf.begin() + 40));
  expect_refused(load_firmware_image(elf_path, kRegion), "not an ELF file (or truncated)");
}

TEST(FirmwareImage, BadHexRecordsNameTheLine) {
  std::string hex = to_hex(make_image(kBoardIdStm32f405), kRegion.load_address);
  const std::size_t third_line = hex.find('\n', hex.find('\n') + 1) + 1;
  hex[third_line + 12] = hex[third_line + 12] == '0' ? '1' : '0';  // a data digit
  const fs::path path = temp_file("bad.hex");
  write_text(path, hex);
  expect_refused(load_firmware_image(path, kRegion), "line 3: checksum mismatch");
}

TEST(FirmwareImage, ElfForAnotherMachineIsRefused) {
  const fs::path path = temp_file("x86.elf");
  write_file(path, to_elf(make_image(kBoardIdStm32f405), kRegion.load_address, 62));
  expect_refused(load_firmware_image(path, kRegion), "is not ARM");
}

TEST(FirmwareImage, MissingFileIsBadInput) {
  expect_refused(load_firmware_image("/nonexistent/app.bin", kRegion), "cannot open the file");
}

TEST(FirmwareImage, TheBuiltProductImageLoadsTheSameFromEveryFormat) {
  const fs::path bin = FLUTTERSCAN_FW_STM32F405_BIN;
  const fs::path hex = fs::path(bin).replace_extension(".hex");
  const fs::path elf = fs::path(bin).replace_extension(".elf");
  if (!fs::exists(bin) || !fs::exists(hex) || !fs::exists(elf))
    GTEST_SKIP() << "no fw-stm32f405 build at " << bin << " (make fw-stm32f405)";
  const auto from_bin = load_firmware_image(bin, kRegion);
  ASSERT_TRUE(from_bin.ok()) << from_bin.error().message;
  for (const auto& path : {hex, elf}) {
    const auto loaded = load_firmware_image(path, kRegion);
    ASSERT_TRUE(loaded.ok()) << loaded.error().message;
    EXPECT_EQ(loaded.value().bytes, from_bin.value().bytes) << path;
  }
}

}  // namespace
}  // namespace flutterscan::device
