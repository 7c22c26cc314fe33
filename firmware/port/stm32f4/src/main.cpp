// The product application on the STM32F405 board: clocks, the Port, the
// controller, the watchdog, and the main loop.
//
// Not yet: USB. The USB OTG FS device driver, the HID command interface and
// DFU come with the USB issue (firmware/README.md); until then this image
// boots, loads the saved configuration and runs it (e.g. a code saved with
// SaveConfig, armed by the host once USB exists), but has no command input.

#include <cstddef>
#include <new>

#include "flutterscan/common/image_header.hpp"
#include "flutterscan/firmware/controller.hpp"
#include "flutterscan/firmware/stm32f4/registers.hpp"
#include "flutterscan/firmware/stm32f4/stm32f4_board.hpp"
#include "flutterscan/firmware/stm32f4/stm32f4_port.hpp"
#include "flutterscan/firmware/stm32f4/system.hpp"

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
    {0, 0, 0},
    kAppBase,
    kAppVectorOffset,
    0,
    0,
    0};

namespace {

constexpr BoardConfig kBoard = stm32f4_board_config();
/// Longer than a 16 KiB sector erase (up to ~0.5 s) at the slowest LSI.
constexpr std::uint32_t kWatchdogTimeoutMs = 2'000;
/// Main loop wake-up period (SysTick): the loop kicks the watchdog on every pass.
constexpr std::uint32_t kMainLoopTickHz = 1'000;

// Static storage in SRAM (never CCM: DMA2 reads the slot tables inside the
// controller), constructed in application_main; no heap.
alignas(Stm32f4Port) std::byte g_port_storage[sizeof(Stm32f4Port)];
alignas(Controller) std::byte g_controller_storage[sizeof(Controller)];

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

[[noreturn]] void application_main() {
  using namespace flutterscan::firmware;
  using namespace flutterscan::firmware::stm32f4;
  const ClockResult clocks = init_clocks();
  auto* port = new (g_port_storage) Stm32f4Port(kBoard.pins, clocks.tree);
  port->init();
  auto* controller = new (g_controller_storage) Controller(*port, kBoard);
  {
    InterruptLock lock;
    controller->start();  // LEDs off, config from flash, brightness
    if (clocks.source == ClockSource::kHsi) controller->on_port_fault();  // no PLL: say so
  }
  port->start_watchdog(kWatchdogTimeoutMs);
  start_main_loop_tick(clocks.tree.hclk_hz);
  for (;;) {
    {
      InterruptLock lock;  // controller.hpp: no port callbacks during controller calls
      if (port->take_fault()) controller->on_port_fault();
      controller->poll();  // kicks the watchdog
      // USB (HID commands, events, DFU detach) will be served here.
    }
    asm volatile("wfi" ::: "memory");
  }
}
