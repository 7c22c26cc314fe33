// Startup for the STM32F405RG (Cortex-M4F), written from PM0214 (section 2.3:
// exception model and vector table) and RM0090 (section 12.2: the 82 maskable
// interrupt positions of the STM32F405/407). The linker script (stm32f405rg.ld)
// places `g_vector_table` at the start of flash and defines the symbols below.

#include <cstdint>

#include "flutterscan/firmware/cortex_m/c_runtime.hpp"
#include "flutterscan/firmware/qemu/registers.hpp"

extern "C" {
// Linker script symbols.
extern std::uint32_t __stack_top__;

[[noreturn]] void Reset_Handler();
void Default_Handler();
void SysTick_Handler();

/// Called by a pure virtual call: cannot happen in correct code; stop here.
void __cxa_pure_virtual() {
  Default_Handler();
}
}

/// The application (main.cpp). Not `main`: ISO C++ forbids calling that.
[[noreturn]] void application_main();

namespace {

using Handler = void (*)();

/// Cortex-M vector table: initial SP, then 15 system exceptions, then the
/// device's interrupts (PM0214 table 17; RM0090 table 61).
constexpr int kSystemVectors = 15;
constexpr int kDeviceInterrupts = 82;

struct VectorTable {
  std::uint32_t* initial_stack_pointer;
  Handler vectors[kSystemVectors + kDeviceInterrupts];
};

constexpr VectorTable make_vector_table() {
  VectorTable table{&__stack_top__, {}};
  for (Handler& vector : table.vectors) vector = Default_Handler;
  table.vectors[0] = Reset_Handler;  // 1: Reset
  // 2..6: NMI, HardFault, MemManage, BusFault, UsageFault -> Default_Handler.
  for (int reserved = 6; reserved <= 9; ++reserved) table.vectors[reserved] = nullptr;  // 7..10
  // 11: SVCall, 12: DebugMonitor -> Default_Handler; 13: reserved.
  table.vectors[12] = nullptr;
  // 14: PendSV -> Default_Handler; 15: SysTick.
  table.vectors[14] = SysTick_Handler;
  return table;
}

}  // namespace

extern "C" {

[[gnu::section(".isr_vector"), gnu::used]] const VectorTable g_vector_table = make_vector_table();

void Default_Handler() {
  // An unexpected exception: stop where a debugger can see it.
  for (;;) {
  }
}

void Reset_Handler() {
  using namespace flutterscan::firmware::qemu;
  // The FPU first: the code is built for hard float (PM0214 4.6.6).
  reg::set_bits(reg::scb::kCpacr, reg::scb::kCpacrFpuFullAccess);
  asm volatile("dsb\n\tisb" ::: "memory");
  reg::at(reg::scb::kVtor) = reinterpret_cast<std::uintptr_t>(&g_vector_table);

  flutterscan::firmware::cortex_m::start_c_runtime();

  application_main();
}

}  // extern "C"
