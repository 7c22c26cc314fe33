// Start-up of the DFU bootloader (flash sector 0, where the STM32F405 boots),
// written from PM0214 (2.3 exception model, vector table; 2.1.3 MSP) and
// RM0090 (12.2, table 61; 8.4 GPIO). At reset, before touching any clock, it
// decides (boot_decision.hpp): the application runs if it did not ask for DFU
// mode (the hand-off word at kBootRequestAddress), the recovery pin (PB2) is
// not held high, fewer than kMaxUnconfirmedStarts starts in a row went
// unconfirmed and fewer than kMaxWatchdogResets resets in a row were watchdog
// resets (RCC_CSR; both counts in the BootRecord after the hand-off word; the
// reset flags cleared with RMVF and handed over in the record) and the image passes
// check_boot_image (header, CRC, load address, vector table at 0x200, SP, PC,
// security_version at or above the security floor in OTP);
// otherwise the C runtime starts and bootloader_main() serves DFU. The jump
// leaves the chip as reset left it, except VTOR, MSP and the independent
// watchdog, started with kBootWatchdogTimeoutMs (GPIOB's clock and PB2's
// pull-down, used to read the pin, are put back to their reset values).

#include <cstdint>
#include <cstring>
#include <span>

#include "flutterscan/common/image_header.hpp"
#include "flutterscan/firmware/boot_decision.hpp"
#include "flutterscan/firmware/cortex_m/c_runtime.hpp"
#include "flutterscan/firmware/security_floor.hpp"
#include "flutterscan/firmware/stm32f4/registers.hpp"
#include "flutterscan/firmware/stm32f4/stm32f4_board.hpp"
#include "flutterscan/firmware/stm32f4/system.hpp"
#include "sector0_protection.hpp"

extern "C" {
extern std::uint32_t __stack_top__;

[[noreturn]] void Reset_Handler();
void Fault_Handler();
void SysTick_Handler();
void OTG_FS_IRQHandler();

void __cxa_pure_virtual() {
  Fault_Handler();
}
}

/// DFU mode (main.cpp).
[[noreturn]] void bootloader_main();

namespace {

static_assert(sizeof(flutterscan::firmware::BootRecord) + 4 <=
                  flutterscan::firmware::stm32f4::kBootRequestReserved,
              "the hand-off word and the BootRecord fit below both images' SRAM");

using Handler = void (*)();
namespace fw = flutterscan::firmware;
namespace stm = flutterscan::firmware::stm32f4;

constexpr int kSystemVectors = 15;
constexpr int kDeviceInterrupts = stm::reg::irq::kCount;

struct VectorTable {
  std::uint32_t* initial_stack_pointer;
  Handler vectors[kSystemVectors + kDeviceInterrupts];
};

constexpr VectorTable make_vector_table() {
  VectorTable table{&__stack_top__, {}};
  for (Handler& vector : table.vectors) vector = Fault_Handler;
  table.vectors[0] = Reset_Handler;
  for (int reserved = 6; reserved <= 9; ++reserved) table.vectors[reserved] = nullptr;
  table.vectors[12] = nullptr;
  table.vectors[14] = SysTick_Handler;
  table.vectors[kSystemVectors + stm::reg::irq::kOtgFs] = OTG_FS_IRQHandler;
  return table;
}

/// Reads the recovery pin (PB2, pulled down) with GPIOB's clock on just for
/// that; GPIOB's PUPDR and the clock go back to their reset values.
bool recovery_pin_held() {
  namespace reg = stm::reg;
  const std::uintptr_t gpio = reg::gpio::port(stm::kRecoveryPort);
  const auto pin = static_cast<std::uint32_t>(stm::kRecoveryPin);
  reg::set_bits(reg::rcc::kAhb1Enr, reg::rcc::kAhb1EnrGpioB);
  (void)reg::read(reg::rcc::kAhb1Enr);  // the clock is on before the port is touched
  const std::uint32_t pupdr = reg::read(gpio + reg::gpio::kPupdr);
  reg::modify(gpio + reg::gpio::kPupdr, 0b11u << (2 * pin), reg::gpio::kPullDown << (2 * pin));
  for (int i = 0; i < 1000; ++i)
    asm volatile("" ::: "memory");  // the pull settles (~60 us at 16 MHz)
  bool held = true;
  for (int i = 0; i < 8; ++i)  // high in every sample: a bounce or glitch is not a request
    held = held && (reg::read(gpio + reg::gpio::kIdr) & (1u << pin)) != 0;
  reg::at(gpio + reg::gpio::kPupdr) = pupdr;
  reg::clear_bits(reg::rcc::kAhb1Enr, reg::rcc::kAhb1EnrGpioB);
  return held;
}

/// Sets VTOR and MSP from the application's vector table and jumps to its reset handler.
[[noreturn]] void start_application() {
  const std::uintptr_t vectors = stm::kAppBase + stm::kAppVectorOffset;
  const std::uint32_t stack = *reinterpret_cast<const volatile std::uint32_t*>(vectors);
  const std::uint32_t reset = *reinterpret_cast<const volatile std::uint32_t*>(vectors + 4);
  stm::reg::at(stm::reg::scb::kVtor) = vectors;
  asm volatile(
      "msr msp, %0\n\t"
      "dsb\n\t"
      "isb\n\t"
      "bx %1" ::"r"(stack),
      "r"(reset)
      : "memory");
  __builtin_unreachable();
}

}  // namespace

extern "C" {

[[gnu::section(".isr_vector"), gnu::used]] const VectorTable g_vector_table = make_vector_table();

void Fault_Handler() {
  // No LEDs are driven by the bootloader; stop and let a reset (or the
  // watchdog the application may have started) bring the chip back.
  for (;;) {
  }
}

void Reset_Handler() {
  volatile std::uint32_t& request = stm::reg::at(stm::kBootRequestAddress);
  fw::BootInputs in;
  in.dfu_requested = request == stm::kBootRequestMagic;
  request = 0;  // once: the next reset runs the application again
  in.boot_pin_held = recovery_pin_held();
  // Sector 0 write-protected in the option bytes (the first boot sets it; a
  // read of FLASH_OPTCR on every later one). A failure changes nothing here:
  // the firmware never erases or programs sector 0 either way.
  (void)protect_bootloader_sector();
  // Why the chip reset (RM0090 7.3.21): the flags stay set until RMVF, so they
  // are cleared here, every time, and the next reset shows only its own; the
  // application gets them from the record (its reset cause).
  const std::uint32_t csr = stm::reg::read(stm::reg::rcc::kCsr);
  stm::reg::set_bits(stm::reg::rcc::kCsr, stm::reg::rcc::kCsrRmvf);
  in.watchdog_reset = (csr & (stm::reg::rcc::kCsrIwdgRstf | stm::reg::rcc::kCsrWwdgRstf)) != 0;
  fw::BootRecord record;
  std::memcpy(&record, reinterpret_cast<const void*>(stm::kBootRecordAddress), sizeof record);
  in.unconfirmed_starts = fw::unconfirmed_starts(record);
  in.watchdog_resets = fw::watchdog_resets(record);
  const auto region = std::span<const std::uint8_t>(
      reinterpret_cast<const std::uint8_t*>(stm::kAppBase), stm::kAppMaxSize);
  // Anti-rollback: the newest confirmed image's security_version (OTP).
  const std::uint8_t floor = fw::security_floor_of(std::span<const std::uint8_t, fw::kSecurityFloorBytes>(
      reinterpret_cast<const std::uint8_t*>(stm::kSecurityFloorAddress), fw::kSecurityFloorBytes));
  in.image = fw::check_boot_image(region, flutterscan::kStm32f405AppRegion, floor);
  const fw::BootDecision decision = fw::decide_boot(in);
  record = fw::make_boot_record(decision.unconfirmed_starts, decision.watchdog_resets,
                                csr & stm::reg::rcc::kCsrResetFlags);
  std::memcpy(reinterpret_cast<void*>(stm::kBootRecordAddress), &record, sizeof record);
  if (decision.target == fw::BootTarget::kApplication) {
    // Whatever the image does from its first instruction on (hang, fault,
    // never feed it), the watchdog resets it, and decide_boot counts it.
    (void)stm::start_independent_watchdog(stm::kBootWatchdogTimeoutMs);
    start_application();
  }

  stm::reg::set_bits(stm::reg::scb::kCpacr, stm::reg::scb::kCpacrFpuFullAccess);
  asm volatile("dsb\n\tisb" ::: "memory");
  stm::reg::at(stm::reg::scb::kVtor) = reinterpret_cast<std::uintptr_t>(&g_vector_table);
  fw::cortex_m::start_c_runtime();
  bootloader_main();
}

}  // extern "C"
