#pragma once
// The flash seam of the bootloader: sector erase, programming and reading of
// the on-chip flash, and the sector map with erase and program time estimates
// (what DFU_GETSTATUS tells the host to wait). port/stm32f4 implements it with
// the flash interface of RM0090 chapter 3, port/sim with a virtual flash.
// Freestanding C++20: no heap, no exceptions, no RTTI.

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

namespace flutterscan::firmware {

/// \brief One erasable sector.
struct FlashSector {
  std::uint32_t base;
  std::uint32_t size;
  std::uint32_t erase_ms;  ///< typical erase time (what the host is told to wait)
};

/// \brief A part's flash: its sectors in address order, and how long programming takes.
struct FlashLayout {
  std::span<const FlashSector> sectors;
  std::uint32_t program_ms_per_kib;  ///< typical time to program 1 KiB

  /// \brief The sector holding `address`, or -1.
  constexpr int sector_of(std::uint32_t address) const {
    for (std::size_t s = 0; s < sectors.size(); ++s)
      if (address >= sectors[s].base && address - sectors[s].base < sectors[s].size)
        return static_cast<int>(s);
    return -1;
  }
};

/// STM32F405/407 with 1 MiB (RM0090 table 5): four 16 KiB, one 64 KiB and seven
/// 128 KiB sectors. Erase times: the datasheet's (DS8626, "Flash memory
/// programming") typical figures at x32 parallelism (16 KiB 250 ms, 64 KiB
/// 550 ms, 128 KiB 1 s; the maxima are twice that); word programming 16 us
/// typical, 256 words per KiB: 4.1 ms, rounded up to 5 ms. Not yet measured
/// on a chip. A host that polls early only waits longer for the answer (the
/// CPU stalls on flash while it erases).
inline constexpr std::array<FlashSector, 12> kStm32f405FlashSectors{{
    {0x08000000, 16 * 1024, 250},
    {0x08004000, 16 * 1024, 250},
    {0x08008000, 16 * 1024, 250},
    {0x0800C000, 16 * 1024, 250},
    {0x08010000, 64 * 1024, 550},
    {0x08020000, 128 * 1024, 1000},
    {0x08040000, 128 * 1024, 1000},
    {0x08060000, 128 * 1024, 1000},
    {0x08080000, 128 * 1024, 1000},
    {0x080A0000, 128 * 1024, 1000},
    {0x080C0000, 128 * 1024, 1000},
    {0x080E0000, 128 * 1024, 1000},
}};
inline constexpr FlashLayout kStm32f405Flash{kStm32f405FlashSectors, 5};

/// \brief Programming goes in words of this many bytes at addresses that are
/// multiples of it (the STM32F4's x32 parallelism, RM0090 3.5.4): a program
/// call at any other address fails; a last word shorter than this is padded
/// with erased bytes (0xFF), which leave its cells as they are.
inline constexpr std::uint32_t kFlashProgramAlignment = 4;

/// \brief Outcome of a flash operation.
enum class FlashResult : std::uint8_t { kOk, kEraseFailed, kProgramFailed, kBadAddress };

/// \brief The flash the bootloader writes.
class Flash {
 public:
  /// \brief Erases sector `sector` of the layout (every byte 0xFF).
  virtual FlashResult erase_sector(int sector) = 0;
  /// \brief Programs `data` at `address`, a multiple of kFlashProgramAlignment
  /// (erased cells only; 0 bits can't become 1).
  virtual FlashResult program(std::uint32_t address, std::span<const std::uint8_t> data) = 0;
  /// \brief The `size` bytes at `address` (memory-mapped on the MCU); empty if out of range.
  virtual std::span<const std::uint8_t> read(std::uint32_t address, std::size_t size) = 0;

 protected:
  ~Flash() = default;
};

}  // namespace flutterscan::firmware
