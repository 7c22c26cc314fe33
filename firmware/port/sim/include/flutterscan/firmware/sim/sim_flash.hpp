#pragma once
// SimFlash: the bootloader's Flash seam as a virtual NOR flash laid out like
// the part (by default the 1 MiB STM32F405: kStm32f405Flash). Erase sets a
// sector to 0xFF; programming can only clear bits (cell &= data), so writing
// over unerased data shows up in the bootloader's verify. Every erase and
// program is counted per sector, so tests can prove a sector (the
// bootloader's) was never touched; failures can be injected. Host only.

#include <cstdint>
#include <span>
#include <vector>

#include "flutterscan/firmware/flash.hpp"

namespace flutterscan::firmware::sim {

/// \brief Virtual flash.
class SimFlash final : public Flash {
 public:
  /// \brief Flash laid out as `layout`, every byte erased.
  explicit SimFlash(const FlashLayout& layout = kStm32f405Flash);

  // Flash ---------------------------------------------------------------------
  FlashResult erase_sector(int sector) override;
  FlashResult program(std::uint32_t address, std::span<const std::uint8_t> data) override;
  std::span<const std::uint8_t> read(std::uint32_t address, std::size_t size) override;

  // Test access ---------------------------------------------------------------
  /// \brief Writes `data` at `address` directly (a programmer at the factory):
  /// erases nothing, counts nothing.
  void load(std::uint32_t address, std::span<const std::uint8_t> data);
  /// \brief The bytes of the whole flash (writable, to corrupt them).
  std::span<std::uint8_t> bytes() { return bytes_; }
  std::uint32_t base() const { return base_; }
  const FlashLayout& layout() const { return layout_; }
  int erase_count(int sector) const { return erases_.at(static_cast<std::size_t>(sector)); }
  int program_count(int sector) const { return programs_.at(static_cast<std::size_t>(sector)); }
  /// \brief Back to the state just after construction: every byte erased,
  /// no erase or program counted, no failure injected (reuses the memory).
  void reset();
  /// \brief Power fails during the flash operation (erase or program) numbered
  /// `operation` from now (0: the next): an erase sets only the first `bytes`
  /// bytes of its sector to 0xFF, a program writes only its first `bytes`
  /// bytes; every operation after it fails until restore_power().
  void lose_power_at_operation(int operation, std::size_t bytes) {
    power_loss_countdown_ = operation;
    power_loss_bytes_ = bytes;
  }
  /// \brief Power is back (what the loss left stays).
  void restore_power() {
    power_loss_countdown_ = -1;
    powered_off_ = false;
  }
  /// \brief Erases and programs so far.
  int operations() const { return operations_; }
  /// \brief Makes the next erase (`erase`) or program (`program`) calls fail.
  void set_failures(bool erase, bool program) {
    erase_fails_ = erase;
    program_fails_ = program;
  }

 private:
  FlashLayout layout_;
  std::uint32_t base_;
  std::vector<std::uint8_t> bytes_;
  std::vector<int> erases_;
  std::vector<int> programs_;
  bool erase_fails_ = false;
  bool program_fails_ = false;
  int operations_ = 0;
  int power_loss_countdown_ = -1;
  std::size_t power_loss_bytes_ = 0;
  bool powered_off_ = false;
  /// Counts an operation; the bytes it may complete (all, or a power loss's).
  std::size_t operation_budget(std::size_t bytes);
};

}  // namespace flutterscan::firmware::sim
