// The product application on the STM32F405 board: clocks, the Port, the
// controller, the watchdog, USB (OTG_FS: HID commands and events, DFU
// runtime), and the main loop. The main loop serves USB (the OTG_FS interrupt
// only wakes it), the controller and the watchdog; DFU_DETACH and
// EnterBootloader reset into the bootloader through the hand-off word.

#include <cstddef>
#include <cstring>
#include <new>

#include "flutterscan/common/image_header.hpp"
#include "flutterscan/firmware/boot_decision.hpp"
#include "flutterscan/firmware/command_handler.hpp"
#include "flutterscan/firmware/controller.hpp"
#include "flutterscan/firmware/stm32f4/otg_fs_device.hpp"
#include "flutterscan/firmware/stm32f4/otp_security_floor.hpp"
#include "flutterscan/firmware/stm32f4/registers.hpp"
#include "flutterscan/firmware/stm32f4/stm32f4_board.hpp"
#include "flutterscan/firmware/stm32f4/stm32f4_flash.hpp"
#include "flutterscan/firmware/stm32f4/stm32f4_port.hpp"
#include "flutterscan/firmware/stm32f4/system.hpp"
#include "flutterscan/firmware/usb/application_usb.hpp"
#include "flutterscan/firmware/usb/usb_descriptors.hpp"

namespace flutterscan::firmware::stm32f4 {

/// The image header at the start of the app region. image_size and the CRCs
/// are filled after the link (stamp_image.cmake).
[[gnu::section(".image_header"), gnu::used]] const ImageHeader g_image_header{
    kImageMagic,
    kImageHeaderVersion,
    static_cast<std::uint16_t>(sizeof(ImageHeader)),
    kBoardId,
    FLUTTERSCAN_VERSION_MAJOR,
    FLUTTERSCAN_VERSION_MINOR,
    FLUTTERSCAN_VERSION_PATCH,
    kImageSecurityVersion,
    {0, 0},
    kAppBase,
    kAppVectorOffset,
    0,
    0,
    0};

namespace {

constexpr BoardConfig kBoard = stm32f4_board_config();
constexpr auto kDeviceDescriptor = usb::application_device_descriptor(usb::bcd_device(
    FLUTTERSCAN_VERSION_MAJOR, FLUTTERSCAN_VERSION_MINOR, FLUTTERSCAN_VERSION_PATCH));
/// Longer than the config's 128 KiB sector erase (sector 11: up to 2 s, DS8626)
/// at the slowest LSI.
constexpr std::uint32_t kWatchdogTimeoutMs = 4'000;
/// Main loop wake-up period (SysTick): the loop kicks the watchdog on every pass.
constexpr std::uint32_t kMainLoopTickHz = 1'000;

// Static storage in SRAM (never CCM: DMA2 reads the slot tables inside the
// controller), constructed in application_main; no heap.
alignas(Stm32f4Port) std::byte g_port_storage[sizeof(Stm32f4Port)];
alignas(Controller) std::byte g_controller_storage[sizeof(Controller)];
alignas(CommandHandler) std::byte g_handler_storage[sizeof(CommandHandler)];
alignas(usb::ApplicationUsb) std::byte g_usb_storage[sizeof(usb::ApplicationUsb)];
OtgFsDevice g_otg_fs;

void start_main_loop_tick(std::uint32_t hclk_hz) {
  reg::at(reg::systick::kLoad) = hclk_hz / kMainLoopTickHz - 1;
  reg::at(reg::systick::kVal) = 0;
  reg::modify(reg::scb::kShpr3, 0xFFu << 24, 0xF0u << 24);  // lowest priority
  reg::at(reg::systick::kCtrl) =
      reg::systick::kCtrlEnable | reg::systick::kCtrlTickInt | reg::systick::kCtrlClkSource;
}

}  // namespace
}  // namespace flutterscan::firmware::stm32f4

extern "C" void SysTick_Handler() {
  // Only wakes the main loop from `wfi`.
}

extern "C" void OTG_FS_IRQHandler() {
  // Wakes the main loop, which serves USB (otg_fs_device.hpp).
  flutterscan::firmware::stm32f4::OtgFsDevice::defer_interrupt();
}

[[noreturn]] void application_main() {
  using namespace flutterscan::firmware;
  using namespace flutterscan::firmware::stm32f4;
  const ClockResult clocks = init_clocks();
  auto* port = new (g_port_storage) Stm32f4Port(kBoard.pins, clocks.tree);
  port->init();
  BoardConfig board = kBoard;
  // Stamped after the link, so read from flash, not folded from the initialiser.
  board.build_id = *static_cast<const volatile std::uint32_t*>(&g_image_header.image_crc32);
  auto* controller = new (g_controller_storage) Controller(*port, board);
  auto* handler = new (g_handler_storage) CommandHandler(*controller);
  auto* usb = new (g_usb_storage)
      usb::ApplicationUsb(g_otg_fs, *controller, *handler, kDeviceDescriptor, unique_id());
  g_otg_fs.set_events(usb);
  {
    InterruptLock lock;
    controller->start();  // LEDs off, config from flash, brightness
    if (clocks.source == ClockSource::kHsi) controller->on_port_fault();  // no PLL: say so
  }
  port->start_watchdog(kWatchdogTimeoutMs);
  start_main_loop_tick(clocks.tree.hclk_hz);
  g_otg_fs.init(clocks.tree.hclk_hz);
  BootConfirmation confirmation;
  for (;;) {
    {
      InterruptLock lock;  // controller.hpp: no port callbacks during controller calls
      if (port->take_fault()) controller->on_port_fault();
      g_otg_fs.poll();  // USB events -> device core, HID interface, DFU runtime
      usb->poll();      // commands, replies, events; Controller::poll: watchdog, bootloader
      // A host query answered over configured USB, or USB configured long
      // enough: this image works; the bootloader's count of unconfirmed starts
      // (boot_decision.hpp) goes back to 0.
      if (confirmation.poll(usb->device().configured(), handler->queries_answered(),
                            port->now_us())) {
        BootRecord record;
        std::memcpy(&record, reinterpret_cast<const void*>(kBootRecordAddress), sizeof record);
        record = confirm_boot_record(record);  // the watchdog count stays
        std::memcpy(reinterpret_cast<void*>(kBootRecordAddress), &record, sizeof record);
        // This image works: no older one may run on this board again.
        OtpSecurityFloor floor;
        (void)floor.raise(g_image_header.security_version);
      }
    }
    if (!g_otg_fs.work_pending()) asm volatile("wfi" ::: "memory");
  }
}
