// Start-up of the DFU bootloader (flash sector 0, where the STM32F405 boots),
// written from PM0214 (2.3 exception model, vector table; 2.1.3 MSP) and
// RM0090 (12.2, table 61). At reset, before touching any clock or peripheral,
// it decides (boot_decision.hpp): the application runs if it did not ask for
// DFU mode (the hand-off word at kBootRequestAddress) and its image header and
// CRC check out; otherwise the C runtime starts and bootloader_main() serves
// DFU. The jump leaves the chip as reset left it, except VTOR and MSP.

#include <cstdint>
#include <span>

#include "flutterscan/common/image_header.hpp"
#include "flutterscan/firmware/boot_decision.hpp"
#include "flutterscan/firmware/cortex_m/c_runtime.hpp"
#include "flutterscan/firmware/stm32f4/registers.hpp"
#include "flutterscan/firmware/stm32f4/stm32f4_board.hpp"

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
  const bool dfu_requested = request == stm::kBootRequestMagic;
  request = 0;  // once: the next reset runs the application again
  const auto region = std::span<const std::uint8_t>(
      reinterpret_cast<const std::uint8_t*>(stm::kAppBase), stm::kAppMaxSize);
  if (fw::choose_boot_target(dfu_requested, region, flutterscan::kStm32f405AppRegion) ==
      fw::BootTarget::kApplication)
    start_application();

  stm::reg::set_bits(stm::reg::scb::kCpacr, stm::reg::scb::kCpacrFpuFullAccess);
  asm volatile("dsb\n\tisb" ::: "memory");
  stm::reg::at(stm::reg::scb::kVtor) = reinterpret_cast<std::uintptr_t>(&g_vector_table);
  fw::cortex_m::start_c_runtime();
  bootloader_main();
}

}  // extern "C"
