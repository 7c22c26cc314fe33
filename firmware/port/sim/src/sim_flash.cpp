#include "flutterscan/firmware/sim/sim_flash.hpp"

#include <algorithm>

namespace flutterscan::firmware::sim {

namespace {

/// NOR programming: cells &= data. A function of its own, never inlined, so
/// the fuzz build can leave its per-byte loop uninstrumented
/// (firmware/fuzz/coverage_ignorelist.txt).
[[gnu::noinline]] void nor_program_bytes(std::uint8_t* cells, const std::uint8_t* data,
                                         std::size_t size) {
  for (std::size_t i = 0; i < size; ++i) cells[i] = static_cast<std::uint8_t>(cells[i] & data[i]);
}

}  // namespace

SimFlash::SimFlash(const FlashLayout& layout)
    : layout_(layout),
      base_(layout.sectors.empty() ? 0 : layout.sectors.front().base),
      bytes_(layout.sectors.empty()
                 ? 0
                 : layout.sectors.back().base + layout.sectors.back().size - base_,
             0xFF),
      erases_(layout.sectors.size(), 0),
      programs_(layout.sectors.size(), 0) {}

std::size_t SimFlash::operation_budget(std::size_t bytes) {
  ++operations_;
  if (power_loss_countdown_ < 0 || power_loss_countdown_-- > 0) return bytes;
  powered_off_ = true;
  return std::min(bytes, power_loss_bytes_);
}

FlashResult SimFlash::erase_sector(int sector) {
  if (sector < 0 || static_cast<std::size_t>(sector) >= layout_.sectors.size())
    return FlashResult::kBadAddress;
  ++erases_[static_cast<std::size_t>(sector)];
  if (erase_fails_ || powered_off_) return FlashResult::kEraseFailed;
  const FlashSector& s = layout_.sectors[static_cast<std::size_t>(sector)];
  std::fill_n(bytes_.begin() + (s.base - base_), operation_budget(s.size), std::uint8_t{0xFF});
  return powered_off_ ? FlashResult::kEraseFailed : FlashResult::kOk;
}

FlashResult SimFlash::program(std::uint32_t address, std::span<const std::uint8_t> data) {
  if (address < base_ || address - base_ + data.size() > bytes_.size())
    return FlashResult::kBadAddress;
  // The product's flash_program refuses an unaligned address (errPROG).
  if (address % kFlashProgramAlignment != 0) return FlashResult::kProgramFailed;
  for (std::uint32_t a = address; a < address + data.size();) {
    const int s = layout_.sector_of(a);
    ++programs_[static_cast<std::size_t>(s)];
    a = layout_.sectors[static_cast<std::size_t>(s)].base +
        layout_.sectors[static_cast<std::size_t>(s)].size;
  }
  if (program_fails_ || powered_off_) return FlashResult::kProgramFailed;
  nor_program_bytes(bytes_.data() + (address - base_), data.data(), operation_budget(data.size()));
  return powered_off_ ? FlashResult::kProgramFailed : FlashResult::kOk;
}

void SimFlash::reset() {
  std::fill(bytes_.begin(), bytes_.end(), std::uint8_t{0xFF});
  std::fill(erases_.begin(), erases_.end(), 0);
  std::fill(programs_.begin(), programs_.end(), 0);
  erase_fails_ = false;
  program_fails_ = false;
  operations_ = 0;
  power_loss_countdown_ = -1;
  powered_off_ = false;
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
