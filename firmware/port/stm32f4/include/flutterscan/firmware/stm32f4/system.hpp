#pragma once
// Chip-level services of the stm32f4 image: clock setup, interrupt masking,
// flash programming, the watchdog and the emergency LED shutdown of the fault
// handlers. ARM only.

#include <cstdint>
#include <span>

#include "flutterscan/firmware/port.hpp"
#include "flutterscan/firmware/stm32f4/hardware_math.hpp"

namespace flutterscan::firmware::stm32f4 {

/// \brief Masks interrupts for its lifetime (PRIMASK), restoring the previous state.
class InterruptLock {
 public:
  InterruptLock() { asm volatile("mrs %0, primask\n\tcpsid i" : "=r"(saved_primask_)::"memory"); }
  ~InterruptLock() { asm volatile("msr primask, %0" ::"r"(saved_primask_) : "memory"); }
  InterruptLock(const InterruptLock&) = delete;
  InterruptLock& operator=(const InterruptLock&) = delete;

 private:
  std::uint32_t saved_primask_;
};

/// \brief Where SYSCLK came from.
enum class ClockSource : std::uint8_t {
  kHsePll,  ///< the product setting: HSE 8 MHz -> PLL 168 MHz, USB 48 MHz
  kHsiPll,  ///< the crystal never started: HSI -> PLL 168 MHz (USB unreliable)
  kHsi,     ///< the PLL never locked or the switch failed: HSI 16 MHz, buses /1
};

/// \brief Result of init_clocks().
struct ClockResult {
  ClockSource source = ClockSource::kHsi;
  ClockTree tree;
};

/// \brief HSE 8 MHz -> PLL (M 8, N 336, P 2, Q 7) -> SYSCLK 168 MHz, USB 48 MHz,
/// AHB 168, APB1 42, APB2 84 MHz, flash 5 wait states with prefetch and caches.
/// Every ready flag is polled a bounded number of times; a flag that never sets
/// falls back (HSI as PLL input, then HSI alone). Call once, first thing.
ClockResult init_clocks();

/// \brief Erases flash sector `sector` (bounded wait; kError on a flash error or timeout).
PortStatus flash_erase_sector(int sector);
/// \brief Programs `data` at `address` (word-aligned, erased) in 32-bit words
/// (PSIZE x32; a partial last word is padded with 0xFF). Verifies every word.
PortStatus flash_program(std::uint32_t address, std::span<const std::uint8_t> data);

/// \brief Starts the independent watchdog (or, running already, sets its new
/// timeout) with `timeout_ms` at the nominal LSI and reloads it; false if the
/// timeout is out of the IWDG's range. Stopped only by a reset (RM0090 21.3).
bool start_independent_watchdog(std::uint32_t timeout_ms);

/// \brief Programs `words` at `address` in the OTP area (x32; 0 bits only, OTP
/// is never erased) and verifies them. kError on a flash error or timeout.
PortStatus otp_program(std::uint32_t address, std::span<const std::uint32_t> words);

/// \brief Turns every LED of the board off and stops the slot DMA, from any
/// context (fault handlers): touches registers only, needs no object.
void emergency_leds_off();

}  // namespace flutterscan::firmware::stm32f4
