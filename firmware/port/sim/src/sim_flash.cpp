#include "flutterscan/firmware/sim/sim_flash.hpp"

#include <algorithm>

namespace flutterscan::firmware::sim {

SimFlash::SimFlash(const FlashLayout& layout)
    : layout_(layout),
      base_(layout.sectors.empty() ? 0 : layout.sectors.front().base),
      bytes_(layout.sectors.empty()
                 ? 0
                 : layout.sectors.back().base + layout.sectors.back().size - base_,
             0xFF),
      erases_(layout.sectors.size(), 0),
      programs_(layout.sectors.size(), 0) {}

FlashResult SimFlash::erase_sector(int sector) {
  if (sector < 0 || static_cast<std::size_t>(sector) >= layout_.sectors.size())
    return FlashResult::kBadAddress;
  ++erases_[static_cast<std::size_t>(sector)];
  if (erase_fails_) return FlashResult::kEraseFailed;
  const FlashSector& s = layout_.sectors[static_cast<std::size_t>(sector)];
  std::fill_n(bytes_.begin() + (s.base - base_), s.size, std::uint8_t{0xFF});
  return FlashResult::kOk;
}

FlashResult SimFlash::program(std::uint32_t address, std::span<const std::uint8_t> data) {
  if (address < base_ || address - base_ + data.size() > bytes_.size())
    return FlashResult::kBadAddress;
  for (std::uint32_t a = address; a < address + data.size();) {
    const int s = layout_.sector_of(a);
    ++programs_[static_cast<std::size_t>(s)];
    a = layout_.sectors[static_cast<std::size_t>(s)].base +
        layout_.sectors[static_cast<std::size_t>(s)].size;
  }
  if (program_fails_) return FlashResult::kProgramFailed;
  for (std::size_t i = 0; i < data.size(); ++i) bytes_[address - base_ + i] &= data[i];
  return FlashResult::kOk;
}

std::span<const std::uint8_t> SimFlash::read(std::uint32_t address, std::size_t size) {
  if (address < base_ || address - base_ + size > bytes_.size()) return {};
  return std::span<const std::uint8_t>(bytes_).subspan(address - base_, size);
}

void SimFlash::load(std::uint32_t address, std::span<const std::uint8_t> data) {
  if (address < base_ || address - base_ + data.size() > bytes_.size()) return;
  std::copy(data.begin(), data.end(), bytes_.begin() + (address - base_));
}

}  // namespace flutterscan::firmware::sim
