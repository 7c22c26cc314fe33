#include "device/firmware_image.hpp"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <map>

namespace flutterscan::device {

namespace {

using Bytes = std::vector<std::uint8_t>;

std::string hex32(std::uint32_t value) {
  char text[16];
  std::snprintf(text, sizeof text, "0x%08X", value);
  return text;
}

/// Collects (address, bytes) pieces and lays them out flat from the region start.
class FlatBuilder {
 public:
  FlatBuilder(const AppRegion& region, std::string source)
      : region_(region), source_(std::move(source)) {}

  /// Places `data` at `address`; an error message if it leaves the region or overlaps.
  std::string place(std::uint64_t address, std::span<const std::uint8_t> data,
                    const std::string& where) {
    if (data.empty()) return {};
    const std::uint64_t begin = region_.load_address;
    const std::uint64_t end = begin + region_.max_size;
    if (address < begin || address + data.size() > end)
      return source_ + ": " + where + " puts " + std::to_string(data.size()) + " bytes at " +
             hex32(static_cast<std::uint32_t>(address)) + ", outside the application region " +
             hex32(region_.load_address) + ".." + hex32(static_cast<std::uint32_t>(end - 1)) +
             " (an image for another board?)";
    const auto offset = static_cast<std::size_t>(address - begin);
    if (bytes_.size() < offset + data.size()) {
      bytes_.resize(offset + data.size(), 0);
      written_.resize(offset + data.size(), false);
    }
    for (std::size_t i = 0; i < data.size(); ++i) {
      if (written_[offset + i] && bytes_[offset + i] != data[i])
        return source_ + ": " + where + " overwrites byte " +
               hex32(static_cast<std::uint32_t>(address + i)) + " with a different value";
      bytes_[offset + i] = data[i];
      written_[offset + i] = true;
    }
    return {};
  }

  Bytes take() { return std::move(bytes_); }

 private:
  AppRegion region_;
  std::string source_;
  Bytes bytes_;
  std::vector<bool> written_;
};

int hex_digit(std::uint8_t c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  return -1;
}

Expected<Bytes> flatten_intel_hex(std::span<const std::uint8_t> content, const AppRegion& region,
                                  const std::string& source) {
  FlatBuilder flat(region, source);
  std::uint32_t base = 0;
  bool saw_end = false;
  std::size_t line_number = 0;
  std::size_t pos = 0;
  while (pos < content.size()) {
    std::size_t end = pos;
    while (end < content.size() && content[end] != '\n') ++end;
    ++line_number;
    std::size_t stop = end;
    while (stop > pos && (content[stop - 1] == '\r' || content[stop - 1] == ' ')) --stop;
    const auto line = content.subspan(pos, stop - pos);
    pos = end + 1;
    const std::string where = "line " + std::to_string(line_number);
    if (line.empty()) continue;
    if (saw_end)
      return fail<Bytes>(ErrorKind::kBadInput,
                         source + ": " + where + ": data after the end-of-file record");
    if (line[0] != ':' || line.size() < 11 || line.size() % 2 == 0)
      return fail<Bytes>(ErrorKind::kBadInput, source + ": " + where + ": not an Intel HEX record");
    Bytes record;
    for (std::size_t i = 1; i + 1 < line.size(); i += 2) {
      const int high = hex_digit(line[i]);
      const int low = hex_digit(line[i + 1]);
      if (high < 0 || low < 0)
        return fail<Bytes>(ErrorKind::kBadInput, source + ": " + where + ": bad hex digit");
      record.push_back(static_cast<std::uint8_t>(high * 16 + low));
    }
    const std::size_t length = record[0];
    if (record.size() != length + 5)
      return fail<Bytes>(ErrorKind::kBadInput, source + ": " + where + ": record length " +
                                                   std::to_string(length) +
                                                   " does not match the line");
    std::uint8_t sum = 0;
    for (const std::uint8_t byte : record) sum = static_cast<std::uint8_t>(sum + byte);
    if (sum != 0)
      return fail<Bytes>(ErrorKind::kBadInput, source + ": " + where + ": checksum mismatch");
    const std::uint32_t offset = static_cast<std::uint32_t>(record[1] << 8 | record[2]);
    const std::uint8_t type = record[3];
    const auto data = std::span<const std::uint8_t>(record).subspan(4, length);
    switch (type) {
      case 0x00:  // data
        if (const auto error = flat.place(std::uint64_t{base} + offset, data, where);
            !error.empty())
          return fail<Bytes>(ErrorKind::kBadInput, error);
        break;
      case 0x01:  // end of file
        saw_end = true;
        break;
      case 0x02:  // extended segment address
        if (length != 2)
          return fail<Bytes>(ErrorKind::kBadInput, source + ": " + where + ": bad type 02 record");
        base = static_cast<std::uint32_t>((data[0] << 8 | data[1]) << 4);
        break;
      case 0x04:  // extended linear address
        if (length != 2)
          return fail<Bytes>(ErrorKind::kBadInput, source + ": " + where + ": bad type 04 record");
        base = static_cast<std::uint32_t>(data[0] << 24 | data[1] << 16);
        break;
      case 0x03:  // start segment address
      case 0x05:  // start linear address
        break;
      default:
        return fail<Bytes>(ErrorKind::kBadInput,
                           source + ": " + where + ": unknown record type " + std::to_string(type));
    }
  }
  if (!saw_end)
    return fail<Bytes>(ErrorKind::kBadInput, source + ": no end-of-file record (truncated?)");
  return Expected<Bytes>::success(flat.take());
}

// ELF32 little-endian, read field by field (no host struct layout assumed).
std::uint32_t le32(std::span<const std::uint8_t> bytes, std::size_t at) {
  return static_cast<std::uint32_t>(bytes[at] | bytes[at + 1] << 8 | bytes[at + 2] << 16 |
                                    static_cast<std::uint32_t>(bytes[at + 3]) << 24);
}
std::uint16_t le16(std::span<const std::uint8_t> bytes, std::size_t at) {
  return static_cast<std::uint16_t>(bytes[at] | bytes[at + 1] << 8);
}

Expected<Bytes> flatten_elf(std::span<const std::uint8_t> content, const AppRegion& region,
                            const std::string& source) {
  constexpr std::size_t kElfHeaderSize = 52;
  constexpr std::size_t kProgramHeaderSize = 32;
  constexpr std::uint16_t kMachineArm = 40;
  constexpr std::uint32_t kPtLoad = 1;
  auto bad = [&](const std::string& why) {
    return fail<Bytes>(ErrorKind::kBadInput, source + ": " + why);
  };
  if (content.size() < kElfHeaderSize || std::memcmp(content.data(),
                                                     "\x7f"
                                                     "ELF",
                                                     4) != 0)
    return bad("not an ELF file (or truncated)");
  if (content[4] != 1) return bad("not a 32-bit ELF file (an image for another machine?)");
  if (content[5] != 1) return bad("not a little-endian ELF file");
  if (le16(content, 18) != kMachineArm)
    return bad("ELF machine " + std::to_string(le16(content, 18)) + " is not ARM (40)");
  const std::uint32_t phoff = le32(content, 28);
  const std::uint16_t phentsize = le16(content, 42);
  const std::uint16_t phnum = le16(content, 44);
  if (phnum == 0) return bad("ELF file without program headers");
  if (phentsize < kProgramHeaderSize ||
      std::uint64_t{phoff} + std::uint64_t{phnum} * phentsize > content.size())
    return bad("ELF program headers run past the end of the file (truncated?)");
  FlatBuilder flat(region, source);
  bool placed = false;
  for (std::uint16_t i = 0; i < phnum; ++i) {
    const std::size_t at = phoff + std::size_t{i} * phentsize;
    if (le32(content, at) != kPtLoad) continue;
    const std::uint32_t offset = le32(content, at + 4);
    const std::uint32_t paddr = le32(content, at + 12);
    const std::uint32_t filesz = le32(content, at + 16);
    if (filesz == 0) continue;  // .bss, stack: nothing to flash
    const std::string where = "segment " + std::to_string(i);
    if (std::uint64_t{offset} + filesz > content.size())
      return bad(where + " runs past the end of the file (truncated?)");
    if (const auto error = flat.place(paddr, content.subspan(offset, filesz), "ELF " + where);
        !error.empty())
      return fail<Bytes>(ErrorKind::kBadInput, error);
    placed = true;
  }
  if (!placed) return bad("no loadable segment with contents");
  return Expected<Bytes>::success(flat.take());
}

}  // namespace

ImageFormat guess_image_format(const std::filesystem::path& path,
                               std::span<const std::uint8_t> content) {
  if (content.size() >= 4 && std::memcmp(content.data(),
                                         "\x7f"
                                         "ELF",
                                         4) == 0)
    return ImageFormat::kElf;
  auto extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (extension == ".elf") return ImageFormat::kElf;
  if (extension == ".hex" || extension == ".ihex" || extension == ".ihx")
    return ImageFormat::kIntelHex;
  if (extension != ".bin" && !content.empty() && content[0] == ':') return ImageFormat::kIntelHex;
  return ImageFormat::kBinary;
}

Expected<std::vector<std::uint8_t>> flatten_image(std::span<const std::uint8_t> content,
                                                  ImageFormat format, const AppRegion& region,
                                                  const std::string& source) {
  switch (format) {
    case ImageFormat::kIntelHex:
      return flatten_intel_hex(content, region, source);
    case ImageFormat::kElf:
      return flatten_elf(content, region, source);
    case ImageFormat::kBinary:
      break;
  }
  if (content.size() > region.max_size)
    return fail<Bytes>(ErrorKind::kBadInput, source + ": " + std::to_string(content.size()) +
                                                 " bytes do not fit the application region (" +
                                                 std::to_string(region.max_size) + " bytes)");
  return Expected<Bytes>::success(Bytes(content.begin(), content.end()));
}

std::string image_check_text(ImageCheck check) {
  switch (check) {
    case ImageCheck::kOk:
      return "valid";
    case ImageCheck::kTooShort:
      return "truncated: shorter than its header says";
    case ImageCheck::kBadMagic:
      return "no flutterscan application header at its start (wrong file?)";
    case ImageCheck::kBadHeader:
      return "image header corrupt (unknown version or size, or header CRC mismatch)";
    case ImageCheck::kWrongBoard:
      return "built for another board";
    case ImageCheck::kBadLayout:
      return "impossible layout (vector table offset or size) for this board's flash";
    case ImageCheck::kImageCrcMismatch:
      return "corrupt: image CRC-32 does not match its header";
  }
  return "invalid";
}

std::optional<AppRegion> app_region_for_board(std::uint16_t board_id) {
  if (board_id == kStm32f405AppRegion.board_id) return kStm32f405AppRegion;
  return std::nullopt;
}

Expected<FirmwareImage> check_firmware_image(std::vector<std::uint8_t> flat,
                                             const AppRegion& region, const std::string& source) {
  const ImageCheck check = check_image(flat, region.board_id, region.max_size);
  if (check != ImageCheck::kOk) {
    std::string message = source + ": refused, " + image_check_text(check);
    if (check == ImageCheck::kWrongBoard)
      message += " (image board id " + std::to_string(read_image_header(flat).board_id) +
                 ", this controller's is " + std::to_string(region.board_id) + ")";
    return fail<FirmwareImage>(ErrorKind::kBadInput, message);
  }
  FirmwareImage image;
  image.header = read_image_header(flat);
  if (image.header.load_address != region.load_address)
    return fail<FirmwareImage>(
        ErrorKind::kBadInput, source + ": refused, linked for " + hex32(image.header.load_address) +
                                  " but this board's application starts at " +
                                  hex32(region.load_address));
  flat.resize(image.header.image_size);  // anything after the image is not flashed
  image.bytes = std::move(flat);
  image.source = source;
  return Expected<FirmwareImage>::success(std::move(image));
}

Expected<FirmwareImage> load_firmware_image(const std::filesystem::path& path,
                                            const AppRegion& region) {
  const std::string source = path.string();
  std::ifstream file(path, std::ios::binary);
  if (!file) return fail<FirmwareImage>(ErrorKind::kBadInput, source + ": cannot open the file");
  const Bytes content((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  if (file.bad()) return fail<FirmwareImage>(ErrorKind::kBadInput, source + ": read error");
  if (content.empty()) return fail<FirmwareImage>(ErrorKind::kBadInput, source + ": empty file");
  const ImageFormat format = guess_image_format(path, content);
  auto flat = flatten_image(content, format, region, source);
  if (!flat.ok()) return fail<FirmwareImage>(flat.error());
  return check_firmware_image(std::move(flat.value()), region, source);
}

}  // namespace flutterscan::device
