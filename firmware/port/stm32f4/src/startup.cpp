// Startup of the stm32f4 application image, written from PM0214 (2.3: exception
// model, vector table) and RM0090 (12.2, table 61: the 82 interrupt positions
// of the STM32F405/407). The linker script (stm32f405rg_app.ld) places the
// image header at the start of the app region and `g_vector_table` 0x200 after it.

#include <cstdint>

#include "flutterscan/firmware/cortex_m/c_runtime.hpp"
#include "flutterscan/firmware/stm32f4/registers.hpp"
#include "flutterscan/firmware/stm32f4/system.hpp"

extern "C" {
// Linker script symbols.
extern std::uint32_t __stack_top__;

[[noreturn]] void Reset_Handler();
void Default_Handler();
void Fault_Handler();
void SysTick_Handler();
void TIM2_IRQHandler();
void DMA2_Stream5_IRQHandler();
void OTG_FS_IRQHandler();

/// Called by a pure virtual call: cannot happen in correct code.
void __cxa_pure_virtual() {
  Fault_Handler();
}
}

/// The application (main.cpp). Not `main`: ISO C++ forbids calling that.
[[noreturn]] void application_main();

namespace {

using Handler = void (*)();

constexpr int kSystemVectors = 15;
constexpr int kDeviceInterrupts = flutterscan::firmware::stm32f4::reg::irq::kCount;

struct VectorTable {
  std::uint32_t* initial_stack_pointer;
  Handler vectors[kSystemVectors + kDeviceInterrupts];
};

/// Index in `vectors` of device interrupt `irq` (exception number 16 + irq).
constexpr int device_vector(int irq) {
  return kSystemVectors + irq;
}

constexpr VectorTable make_vector_table() {
  namespace irq = flutterscan::firmware::stm32f4::reg::irq;
  VectorTable table{&__stack_top__, {}};
  for (Handler& vector : table.vectors) vector = Default_Handler;
  table.vectors[0] = Reset_Handler;  // 1: Reset
  // 2..6: NMI, HardFault, MemManage, BusFault, UsageFault: LEDs off, then stop.
  for (int fault = 1; fault <= 5; ++fault) table.vectors[fault] = Fault_Handler;
  for (int reserved = 6; reserved <= 9; ++reserved) table.vectors[reserved] = nullptr;  // 7..10
  table.vectors[12] = nullptr;  // 13: reserved
  table.vectors[14] = SysTick_Handler;
  table.vectors[device_vector(irq::kTim2)] = TIM2_IRQHandler;
  table.vectors[device_vector(irq::kDma2Stream5)] = DMA2_Stream5_IRQHandler;
  table.vectors[device_vector(irq::kOtgFs)] = OTG_FS_IRQHandler;
  return table;
}

}  // namespace

extern "C" {

[[gnu::section(".isr_vector"), gnu::used]] const VectorTable g_vector_table = make_vector_table();

void Default_Handler() {
  Fault_Handler();  // an interrupt nobody enabled: treat as a fault
}

void Fault_Handler() {
  // Every LED off, then wait for the watchdog (if started) to reset the chip.
  flutterscan::firmware::stm32f4::emergency_leds_off();
  for (;;) {
  }
}

void Reset_Handler() {
  using namespace flutterscan::firmware::stm32f4;
  // LEDs are inputs (floating, pulled down on the board) until the port makes them outputs.
  reg::set_bits(reg::scb::kCpacr, reg::scb::kCpacrFpuFullAccess);  // hard float (PM0214 4.6.6)
  asm volatile("dsb\n\tisb" ::: "memory");
  reg::at(reg::scb::kVtor) = reinterpret_cast<std::uintptr_t>(&g_vector_table);

  flutterscan::firmware::cortex_m::start_c_runtime();

  application_main();
}

}  // extern "C"
