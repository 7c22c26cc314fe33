#pragma once
// The OTG_FS device-controller driver of the STM32F405 (RM0090 chapter 34,
// device mode, full speed, no DMA): the UsbDeviceController seam on the chip.
// PA11/PA12 are DM/DP (AF10); VBUS sensing is off (NOVBUSSENS: the board is
// bus powered, so VBUS is present whenever it is connected; PA9 stays free).
//
// Interrupts are deferred: OTG_FS_IRQHandler only clears GAHBCFG.GINTMSK (so
// the interrupt line drops) and the main loop calls poll(), which handles every
// pending core event, calls the device core (UsbDeviceEvents) from main-loop
// context and re-enables the interrupt. So the core, the HID interface and the
// controller never run in interrupt context on behalf of USB.
//
// EP0 traffic is handled one packet at a time (XFRC after each); SETUPs are
// processed at the STUP interrupt; SET_ADDRESS goes to DCFG at once (the core
// sends the status stage with the old address, RM0090 34.17.5).
// Not yet run on a chip (firmware/README.md).

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "flutterscan/firmware/stm32f4/otg_fs_layout.hpp"
#include "flutterscan/firmware/usb/usb_device_controller.hpp"

namespace flutterscan::firmware::stm32f4 {

/// \brief The OTG_FS core in device mode.
class OtgFsDevice final : public usb::UsbDeviceController {
 public:
  /// \brief Where core events go (set before init()).
  void set_events(usb::UsbDeviceEvents* events) { events_ = events; }
  /// \brief Clocks, pins, core reset, device mode, FIFOs, interrupt; then
  /// connects (pull-up on DP). `hclk_hz` sets the turnaround time.
  void init(std::uint32_t hclk_hz);
  /// \brief Main-loop work: every pending core event, then the interrupt re-enabled.
  void poll();
  /// \brief Core events are waiting for poll().
  bool work_pending() const;
  /// \brief Soft disconnect (pull-up off): the host sees an unplug.
  void disconnect();
  /// \brief OTG_FS_IRQHandler's work: mask the core's interrupt until poll().
  static void defer_interrupt();

  // UsbDeviceController ------------------------------------------------------
  void set_address(std::uint8_t address) override;
  void open_endpoint(const usb::EndpointConfig& endpoint) override;
  void close_endpoint(std::uint8_t address) override;
  void set_stall(std::uint8_t address, bool stalled) override;
  bool transmit(std::uint8_t address, std::span<const std::uint8_t> packet) override;
  void receive(std::uint8_t address) override;
  void ep0_transmit(std::span<const std::uint8_t> data, bool zero_length_end) override;
  void ep0_receive(std::span<std::uint8_t> buffer) override;
  void ep0_status() override;
  void ep0_stall() override;

 private:
  /// Where the current control transfer is.
  enum class Ep0Stage : std::uint8_t {
    kIdle,
    kInData,     ///< sending the IN data stage
    kOutStatus,  ///< waiting for the host's zero-length OUT status packet
    kOutData,    ///< receiving the OUT data stage
    kInStatus,   ///< sending the zero-length IN status packet
  };

  void bus_reset();
  void enumeration_done();
  void read_rx_fifo();
  void out_endpoint_events();
  void in_endpoint_events();
  void send_ep0_packet();
  void arm_ep0_setup();
  void arm_ep0_out();
  void write_fifo(int ep, std::span<const std::uint8_t> data);
  void flush_tx_fifo(std::uint32_t fifo);

  usb::UsbDeviceEvents* events_ = nullptr;
  std::array<std::uint8_t, 8> setup_{};

  Ep0Stage ep0_stage_ = Ep0Stage::kIdle;
  std::span<const std::uint8_t> ep0_in_;
  std::size_t ep0_in_sent_ = 0;
  bool ep0_zero_length_end_ = false;
  std::span<std::uint8_t> ep0_out_;
  std::size_t ep0_out_received_ = 0;

  std::array<std::uint16_t, reg::otg::kEndpoints> out_max_packet_{};
  std::array<std::array<std::uint8_t, 64>, reg::otg::kEndpoints> out_packet_{};
  std::array<std::size_t, reg::otg::kEndpoints> out_length_{};
  std::uint32_t in_busy_ = 0;  ///< bit n: IN endpoint n has a packet queued
};

}  // namespace flutterscan::firmware::stm32f4
