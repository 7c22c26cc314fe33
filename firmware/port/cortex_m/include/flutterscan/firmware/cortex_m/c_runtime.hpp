#pragma once
// The C/C++ runtime set-up every Cortex-M image of this project does in its
// reset handler before the application runs: .data copied from its load image
// in flash, .bss zeroed, static constructors run. The symbols come from the
// image's linker script.

#include <cstdint>

extern "C" {
extern std::uint32_t __data_load__;
extern std::uint32_t __data_start__;
extern std::uint32_t __data_end__;
extern std::uint32_t __bss_start__;
extern std::uint32_t __bss_end__;
using InitFunction = void (*)();
extern InitFunction __preinit_array_start[];
extern InitFunction __preinit_array_end[];
extern InitFunction __init_array_start[];
extern InitFunction __init_array_end[];
}

namespace flutterscan::firmware::cortex_m {

/// \brief Copies .data, zeroes .bss and runs the static constructors.
inline void start_c_runtime() {
  const std::uint32_t* source = &__data_load__;
  for (std::uint32_t* word = &__data_start__; word < &__data_end__; ++word) *word = *source++;
  for (std::uint32_t* word = &__bss_start__; word < &__bss_end__; ++word) *word = 0;
  for (InitFunction* f = __preinit_array_start; f < __preinit_array_end; ++f) (*f)();
  for (InitFunction* f = __init_array_start; f < __init_array_end; ++f) (*f)();
}

}  // namespace flutterscan::firmware::cortex_m
