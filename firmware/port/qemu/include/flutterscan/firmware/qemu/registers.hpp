#pragma once
// The few STM32F405 and Cortex-M4 registers the QEMU image touches, written
// from the reference manuals: PM0214 (Cortex-M4 programming manual: SCB,
// SysTick) and RM0090 (STM32F405/407: memory map, RCC, GPIO, USART).
// QEMU 7.2's netduinoplus2 models SysTick and USART1; RCC and GPIO are
// unimplemented there (reads return 0, writes are logged by `-d unimp`).
// ARM only: included by the fw-qemu image, never by host code.

#include <cstdint>

namespace flutterscan::firmware::qemu::reg {

/// \brief The 32-bit memory-mapped register at `address`.
inline volatile std::uint32_t& at(std::uintptr_t address) {
  return *reinterpret_cast<volatile std::uint32_t*>(address);
}

/// \brief Sets `bits` in the register at `address` (read-modify-write).
inline void set_bits(std::uintptr_t address, std::uint32_t bits) {
  volatile std::uint32_t& r = at(address);
  r = r | bits;
}

/// \brief Replaces the bits under `mask` with `value` (already shifted) at `address`.
inline void modify(std::uintptr_t address, std::uint32_t mask, std::uint32_t value) {
  volatile std::uint32_t& r = at(address);
  r = (r & ~mask) | (value & mask);
}

// PM0214 section 4.4: System control block.
namespace scb {
inline constexpr std::uintptr_t kIcsr = 0xE000ED04;        ///< interrupt control and state
inline constexpr std::uintptr_t kVtor = 0xE000ED08;        ///< vector table offset
inline constexpr std::uintptr_t kCpacr = 0xE000ED88;       ///< coprocessor access control (4.6.1)
inline constexpr std::uint32_t kIcsrPendStSet = 1u << 26;  ///< SysTick exception pending
inline constexpr std::uint32_t kIcsrPendStClr = 1u << 25;  ///< clears a pending SysTick
/// CP10 and CP11 (the FPU) full access: bits 20..23.
inline constexpr std::uint32_t kCpacrFpuFullAccess = 0xFu << 20;
}  // namespace scb

// PM0214 section 4.5: SysTick timer (24-bit down counter).
namespace systick {
inline constexpr std::uintptr_t kCtrl = 0xE000E010;  ///< STK_CTRL
inline constexpr std::uintptr_t kLoad = 0xE000E014;  ///< STK_LOAD: reload value (24 bits)
inline constexpr std::uintptr_t kVal = 0xE000E018;   ///< STK_VAL: current value; a write clears it
inline constexpr std::uint32_t kCtrlEnable = 1u << 0;
inline constexpr std::uint32_t kCtrlTickInt = 1u << 1;    ///< exception at count to 0
inline constexpr std::uint32_t kCtrlClkSource = 1u << 2;  ///< 1: processor clock (AHB)
inline constexpr std::uint32_t kMaxReload = 0x00FFFFFF;
}  // namespace systick

// RM0090 section 7.3: Reset and clock control (base 0x40023800).
namespace rcc {
inline constexpr std::uintptr_t kAhb1Enr = 0x40023830;  ///< AHB1 peripheral clock enable
inline constexpr std::uintptr_t kApb2Enr = 0x40023844;  ///< APB2 peripheral clock enable
inline constexpr std::uint32_t kAhb1EnrGpioA = 1u << 0;
inline constexpr std::uint32_t kApb2EnrUsart1 = 1u << 4;
}  // namespace rcc

// RM0090 section 8.4: GPIO port A (base 0x40020000).
namespace gpioa {
inline constexpr std::uintptr_t kModer = 0x40020000;  ///< 2 bits per pin: 00 in, 01 out, 10 AF
inline constexpr std::uintptr_t kBsrr = 0x40020018;   ///< bit p sets pin p, bit 16+p resets it
inline constexpr std::uintptr_t kAfrh = 0x40020024;   ///< 4 bits per pin 8..15: alternate function
inline constexpr std::uint32_t kModeOutput = 0b01;
inline constexpr std::uint32_t kModeAlternate = 0b10;
}  // namespace gpioa

// RM0090 section 30.6: USART1 (base 0x40011000, on APB2).
namespace usart1 {
inline constexpr std::uintptr_t kSr = 0x40011000;   ///< status
inline constexpr std::uintptr_t kDr = 0x40011004;   ///< data
inline constexpr std::uintptr_t kBrr = 0x40011008;  ///< baud rate
inline constexpr std::uintptr_t kCr1 = 0x4001100C;  ///< control 1
inline constexpr std::uint32_t kSrRxne = 1u << 5;   ///< a received byte waits in DR
inline constexpr std::uint32_t kSrTxe = 1u << 7;    ///< DR is empty: the next byte may go
inline constexpr std::uint32_t kCr1Re = 1u << 2;
inline constexpr std::uint32_t kCr1Te = 1u << 3;
inline constexpr std::uint32_t kCr1Ue = 1u << 13;
/// Alternate function of PA9 (TX) and PA10 (RX) for USART1 (DS8626 table 9).
inline constexpr std::uint32_t kPinAf = 7;
}  // namespace usart1

}  // namespace flutterscan::firmware::qemu::reg
