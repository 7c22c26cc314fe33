// The DFU bootloader's DFU mode: clocks (48 MHz for USB), the OTG_FS driver
// and the core's BootloaderUsb (plain DFU 1.1 over the application region of
// the flash, dfu_mode.hpp). When the host is done (manifest + USB reset, or
// DFU_DETACH with a valid image) it disconnects and resets; the start-up code
// then starts the application. It never erases or writes its own sector
// (DfuMode refuses sectors below the application, flash_erase_sector refuses
// sector 0).

#include <cstddef>
#include <cstring>
#include <new>

#include "flutterscan/common/image_header.hpp"
#include "flutterscan/firmware/boot_decision.hpp"
#include "flutterscan/firmware/flash.hpp"
#include "flutterscan/firmware/stm32f4/otg_fs_device.hpp"
#include "flutterscan/firmware/stm32f4/otp_security_floor.hpp"
#include "flutterscan/firmware/stm32f4/registers.hpp"
#include "flutterscan/firmware/stm32f4/stm32f4_board.hpp"
#include "flutterscan/firmware/stm32f4/stm32f4_flash.hpp"
#include "flutterscan/firmware/stm32f4/system.hpp"
#include "flutterscan/firmware/usb/bootloader_usb.hpp"
#include "flutterscan/firmware/usb/usb_descriptors.hpp"

namespace {

namespace fw = flutterscan::firmware;
namespace stm = flutterscan::firmware::stm32f4;
namespace reg = flutterscan::firmware::stm32f4::reg;

constexpr auto kDeviceDescriptor = fw::usb::bootloader_device_descriptor(fw::usb::bcd_device(
    FLUTTERSCAN_VERSION_MAJOR, FLUTTERSCAN_VERSION_MINOR, FLUTTERSCAN_VERSION_PATCH));

stm::OtgFsDevice g_otg_fs;
stm::Stm32f4Flash g_flash;
stm::OtpSecurityFloor g_security_floor;
alignas(fw::usb::BootloaderUsb) std::byte g_usb_storage[sizeof(fw::usb::BootloaderUsb)];

void start_tick(std::uint32_t hclk_hz) {
  reg::at(reg::systick::kLoad) = hclk_hz / 1000 - 1;  // 1 ms: wakes the loop
  reg::at(reg::systick::kVal) = 0;
  reg::at(reg::systick::kCtrl) =
      reg::systick::kCtrlEnable | reg::systick::kCtrlTickInt | reg::systick::kCtrlClkSource;
}

[[noreturn]] void reset_chip() {
  asm volatile("cpsid i" ::: "memory");
  reg::at(reg::scb::kAircr) = reg::scb::kAircrSystemReset;
  asm volatile("dsb" ::: "memory");
  for (;;) {
  }
}

}  // namespace

extern "C" void SysTick_Handler() {}

extern "C" void OTG_FS_IRQHandler() {
  stm::OtgFsDevice::defer_interrupt();
}

[[noreturn]] void bootloader_main() {
  const stm::ClockResult clocks = stm::init_clocks();
  auto* usb = new (g_usb_storage)
      fw::usb::BootloaderUsb(g_otg_fs, g_flash, g_security_floor, fw::kStm32f405Flash,
                             flutterscan::kStm32f405AppRegion, kDeviceDescriptor, stm::unique_id());
  g_otg_fs.set_events(usb);
  start_tick(clocks.tree.hclk_hz);
  g_otg_fs.init(clocks.tree.hclk_hz);
  for (;;) {
    asm volatile("cpsid i" ::: "memory");
    g_otg_fs.poll();
    // An application that started the watchdog and then reset here: keep it
    // fed (harmless when the watchdog is off).
    reg::at(reg::iwdg::kKr) = reg::iwdg::kKeyReload;
    if (usb->leave_requested()) {
      // The host flashed or detached on purpose: the application gets its
      // kMaxUnconfirmedStarts tries again, and the watchdog count starts at 0.
      const fw::BootRecord record = fw::make_boot_record(0);
      std::memcpy(reinterpret_cast<void*>(stm::kBootRecordAddress), &record, sizeof record);
      g_otg_fs.disconnect();
      for (std::uint32_t i = 0; i < clocks.tree.hclk_hz / 100; ++i) asm volatile("" ::: "memory");
      reset_chip();  // the start-up code starts the checked application
    }
    asm volatile("cpsie i" ::: "memory");
    if (!g_otg_fs.work_pending()) asm volatile("wfi" ::: "memory");
  }
}
