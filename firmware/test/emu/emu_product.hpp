#pragma once
// The product as it leaves the factory, on the emulated chip: the fw-stm32f405
// bootloader ELF's segments and the stamped application image in flash, the
// `wfi` of both main loops marked (Chip::sleep_at), and a stop at the
// application's reset handler.

#include <cstdint>
#include <string>

#include "emu_chip.hpp"
#include "emu_elf.hpp"
#include "flutterscan/firmware/boot_decision.hpp"

namespace flutterscan::firmware::emu {

/// Loads the product into `chip`; "" or why it cannot (no build: the caller skips).
inline std::string load_product(Chip& chip) {
  const auto boot = Elf::load(FLUTTERSCAN_BOOTLOADER_ELF);
  const auto app = Elf::load(FLUTTERSCAN_FW_STM32F405_ELF);
  const auto image = read_file(FLUTTERSCAN_FW_STM32F405_BIN);
  if (!boot || !app || image.empty())
    return "no bootloader / application ELF or image (make fw-stm32f405 builds them)";
  const auto app_sleeps = app->wfi_in("_Z16application_mainv");
  const auto boot_sleeps = boot->wfi_in("_Z15bootloader_mainv");
  if (app_sleeps.size() != 1 || boot_sleeps.size() != 1)
    return "expected one wfi in each main loop (application_main, bootloader_main)";
  for (const auto& s : boot->segments) chip.write(s.address, s.bytes);
  chip.write(kAppBase, image);
  chip.stop_at(get<std::uint32_t>(image, kAppVectorTableOffset + 4), "application");
  chip.sleep_at(app_sleeps[0]);
  chip.sleep_at(boot_sleeps[0]);
  return "";
}

}  // namespace flutterscan::firmware::emu
