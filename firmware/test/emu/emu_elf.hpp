#pragma once
// The emulator tests' ELF reader: the loadable segments of a 32-bit
// little-endian ARM ELF (at their load addresses), symbol values and sizes,
// and where a function sleeps (wfi).

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <optional>
#include <string>
#include <vector>

namespace flutterscan::firmware::emu {

inline std::vector<std::uint8_t> read_file(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) return {};
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

template <typename T>
T get(const std::vector<std::uint8_t>& b, std::size_t at) {
  T v{};
  if (at + sizeof v <= b.size()) std::memcpy(&v, b.data() + at, sizeof v);
  return v;
}

/// The loadable segments of a 32-bit little-endian ARM ELF (at their load
/// addresses) and one symbol's value.
struct Elf {
  struct Segment {
    std::uint32_t address;
    std::vector<std::uint8_t> bytes;
  };
  std::vector<Segment> segments;
  std::vector<std::uint8_t> file;

  static std::optional<Elf> load(const std::string& path) {
    Elf elf;
    elf.file = read_file(path);
    const auto& b = elf.file;
    if (b.size() < 52 ||
        std::memcmp(b.data(),
                    "\x7f"
                    "ELF",
                    4) != 0 ||
        b[4] != 1 || b[5] != 1)
      return std::nullopt;
    const auto phoff = get<std::uint32_t>(b, 28);
    const auto phentsize = get<std::uint16_t>(b, 42);
    const auto phnum = get<std::uint16_t>(b, 44);
    for (std::uint16_t i = 0; i < phnum; ++i) {
      const std::size_t ph = phoff + static_cast<std::size_t>(i) * phentsize;
      if (get<std::uint32_t>(b, ph) != 1) continue;  // PT_LOAD
      const auto offset = get<std::uint32_t>(b, ph + 4);
      const auto paddr = get<std::uint32_t>(b, ph + 12);
      const auto filesz = get<std::uint32_t>(b, ph + 16);
      if (filesz == 0 || offset + filesz > b.size()) continue;
      elf.segments.push_back(
          {paddr, std::vector<std::uint8_t>(b.begin() + offset, b.begin() + offset + filesz)});
    }
    return elf;
  }

  /// The value of symbol `name` (mangled), or 0.
  std::uint32_t symbol(const std::string& name) const { return lookup(name, 4); }
  /// The size of symbol `name` (a function's bytes), or 0.
  std::uint32_t symbol_size(const std::string& name) const { return lookup(name, 8); }
  /// The addresses of the `wfi` instructions (0xBF30) in function `name`.
  std::vector<std::uint32_t> wfi_in(const std::string& name) const {
    const std::uint32_t start = symbol(name) & ~1u;
    const std::uint32_t end = start + symbol_size(name);
    std::vector<std::uint32_t> out;
    for (const Segment& s : segments)
      for (std::uint32_t a = std::max(start, s.address); a + 2 <= end; a += 2) {
        if (a + 2 > s.address + s.bytes.size()) break;
        // A halfword that starts a 32-bit instruction (0b11101/0b11110/0b11111
        // in 15:11) makes the next one its second half: skip it.
        const auto h = get<std::uint16_t>(s.bytes, a - s.address);
        if ((h >> 11) >= 0x1D) {
          a += 2;
          continue;
        }
        if (h == 0xBF30) out.push_back(a);
      }
    return out;
  }

 private:
  std::uint32_t lookup(const std::string& name, std::size_t field) const {
    const auto& b = file;
    const auto shoff = get<std::uint32_t>(b, 32);
    const auto shentsize = get<std::uint16_t>(b, 46);
    const auto shnum = get<std::uint16_t>(b, 48);
    for (std::uint16_t i = 0; i < shnum; ++i) {
      const std::size_t sh = shoff + static_cast<std::size_t>(i) * shentsize;
      if (get<std::uint32_t>(b, sh + 4) != 2) continue;  // SHT_SYMTAB
      const auto offset = get<std::uint32_t>(b, sh + 16);
      const auto size = get<std::uint32_t>(b, sh + 20);
      const auto link = get<std::uint32_t>(b, sh + 24);
      const std::size_t strsh = shoff + static_cast<std::size_t>(link) * shentsize;
      const auto stroff = get<std::uint32_t>(b, strsh + 16);
      for (std::uint32_t s = 0; s + 16 <= size; s += 16) {
        const auto name_at = get<std::uint32_t>(b, offset + s);
        const char* n = reinterpret_cast<const char*>(b.data() + stroff + name_at);
        if (name == n) return get<std::uint32_t>(b, offset + s + field);  // st_value, st_size
      }
    }
    return 0;
  }
};

}  // namespace flutterscan::firmware::emu
