#pragma once
// SimBoard: a whole simulated controller board as the USB host sees it, for the
// unit tests, the HIL harness (hil_tests/, answering usbdevfs and hidraw for
// the real flutterscan binary and dfu-util under umockdev) and the host's
// virtual controller. It holds what survives a reset (the SimPort with its
// LEDs, clock and config page; the SimFlash with the application region; the
// chip's unique ID) and what a reset rebuilds: either
//   - application mode: Controller + CommandHandler + ApplicationUsb (HID
//     interface 0, DFU runtime interface 1; VID 0x1209, PID 0x0001), running
//     "the image in flash": GetInfo reports the firmware version from the
//     application image header and build_id = its image CRC-32; or
//   - bootloader mode: BootloaderUsb (DFU mode interface 0; PID 0x0002) over
//     the SimFlash.
// A reset boots like the chip: the bootloader decision (boot_decision.hpp)
// starts the application if the flash holds a valid image for this board and
// DFU mode was not requested, else stays in the bootloader.
//
// Mode changes happen the way a real board re-enumerates: DFU_DETACH or an
// EnterBootloader command (application -> bootloader), or a successful
// manifest followed by a USB reset or DFU_DETACH (bootloader -> application).
// Each reset builds a fresh USB device (unaddressed, unconfigured) and
// increments epoch(); the callback set with on_reenumerate() is called at the
// end of the host-side call that caused it. The HIL harness then removes the
// old umockdev device, calls enumerate() (what the kernel does at plug-in:
// resets, SET_ADDRESS, descriptors, SET_CONFIGURATION, usbhid's SET_IDLE and
// report descriptor) and adds the new device with sysfs_descriptors(),
// vendor_id()/product_id() and serial().
//
// Host-side calls (the harness's usbdevfs): control_transfer() (SETUP + data
// stage; returns the IN data or STALL), interrupt_out(), interrupt_in() (one
// 64-byte HID report or nothing), bus_reset(). Each runs one main-loop pass
// (poll()) after the transfer, so replies and exposure events are queued on
// the IN endpoint by the time the call returns. Virtual time only moves with
// run_for()/run_until() (strobes and encoder via port()).
// Not thread-safe: one thread drives a board. Host only.

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "flutterscan/common/image_header.hpp"
#include "flutterscan/firmware/boot_decision.hpp"
#include "flutterscan/firmware/command_handler.hpp"
#include "flutterscan/firmware/controller.hpp"
#include "flutterscan/firmware/settings.hpp"
#include "flutterscan/firmware/sim/sim_flash.hpp"
#include "flutterscan/firmware/sim/sim_port.hpp"
#include "flutterscan/firmware/sim/sim_security_floor.hpp"
#include "flutterscan/firmware/sim/sim_usb_controller.hpp"
#include "flutterscan/firmware/usb/application_usb.hpp"
#include "flutterscan/firmware/usb/bootloader_usb.hpp"
#include "flutterscan/firmware/usb/usb_descriptors.hpp"

namespace flutterscan::firmware::sim {

/// \brief Which image the board runs.
enum class BoardMode : std::uint8_t { kApplication, kBootloader };

/// \brief What does not change across resets.
struct SimBoardConfig {
  /// LED pins, guard defaults; board_id must equal region.board_id. The
  /// firmware version and build id come from the image in flash instead.
  BoardConfig board = default_board();
  AppRegion region = kStm32f405AppRegion;
  /// The chip's 96-bit unique ID: the serial number is its 24 hex digits.
  std::array<std::uint8_t, usb::kUniqueIdSize> unique_id{0x31, 0x00, 0x2A, 0x00, 0x05, 0x47,
                                                         0x33, 0x30, 0x38, 0x37, 0x39, 0x36};
  std::uint8_t bootloader_major = 1;  ///< bcdDevice of the bootloader
  std::uint8_t bootloader_minor = 0;
  std::uint8_t bootloader_patch = 0;

  /// \brief The STM32F405 board's pins and id (three LEDs on pins 0..2).
  static BoardConfig default_board() {
    BoardConfig b;
    b.pins = LedPinMap{3, {0, 1, 2, 3}};
    b.board_id = kBoardIdStm32f405;
    return b;
  }
};

/// \brief How long a hub debounces a new connection before resetting it (USB 2.0 7.1.7.3).
inline constexpr std::uint64_t kAttachDebounceUs = 100'000;

/// \brief What the host learned by enumerating the device.
struct Enumeration {
  bool ok = false;
  std::string error;  ///< the first step that failed, if any
  std::vector<std::uint8_t> device_descriptor;
  std::vector<std::uint8_t> configuration_descriptor;  ///< wTotalLength bytes
  std::vector<std::uint8_t> hid_report_descriptor;     ///< application mode only
  std::string manufacturer;
  std::string product;
  std::string serial;
};

/// \brief A stamped application image (header + vector table offset + `size`
/// bytes in all) for `board_id` with version `major.minor.patch` and
/// `security_version`; the payload bytes come from `seed`. What tests and the
/// HIL harness flash.
std::vector<std::uint8_t> make_application_image(std::uint16_t board_id, std::uint8_t major,
                                                 std::uint8_t minor, std::uint8_t patch,
                                                 std::size_t size, std::uint32_t seed = 1,
                                                 std::uint32_t load_address = 0x08008000,
                                                 std::uint8_t security_version = 0);

/// \brief A simulated controller board.
class SimBoard {
 public:
  /// \brief A board with `config`; `initial_image` (if any) is loaded into the
  /// application region as if programmed at the factory; then it resets.
  explicit SimBoard(const SimBoardConfig& config = {},
                    std::span<const std::uint8_t> initial_image = {});
  ~SimBoard();
  SimBoard(const SimBoard&) = delete;
  SimBoard& operator=(const SimBoard&) = delete;

  // Mode ----------------------------------------------------------------------
  BoardMode mode() const { return mode_; }
  /// \brief Increments at every reset (each one is a new USB device to enumerate).
  std::uint32_t epoch() const { return epoch_; }
  /// \brief Called (mode, epoch) after every reset the board makes by itself.
  void on_reenumerate(std::function<void(BoardMode, std::uint32_t)> callback) {
    reenumerate_callback_ = std::move(callback);
  }
  /// \brief Resets the chip (power cycle, reset button; `dfu_requested`: as if
  /// the application had asked for the bootloader). Calls the callback too.
  void reset(bool dfu_requested = false);
  /// \brief A watchdog reset: SRAM (the BootRecord) survives, the bootloader
  /// decides as on the chip (boot_decision.hpp: 3 unconfirmed starts, or 3
  /// watchdog resets, in a row keep it in DFU mode). Calls the callback too.
  void watchdog_reset();
  /// \brief The recovery pin (PB2) held high from now on (or released).
  void set_recovery_pin(bool held) { recovery_pin_ = held; }
  /// \brief Application starts since the last confirmation (the BootRecord).
  std::uint32_t unconfirmed_starts() const { return firmware::unconfirmed_starts(boot_record_); }
  /// \brief Watchdog resets in a row (the BootRecord; confirmation keeps it).
  std::uint32_t watchdog_resets() const { return firmware::watchdog_resets(boot_record_); }

  // Host side (usbdevfs) ----------------------------------------------------------
  ControlResult control_transfer(std::span<const std::uint8_t, 8> setup,
                                 std::span<const std::uint8_t> out_data = {});
  ControlResult control_transfer(std::uint8_t request_type, std::uint8_t request,
                                 std::uint16_t value, std::uint16_t index, std::uint16_t length,
                                 std::span<const std::uint8_t> out_data = {});
  OutResult interrupt_out(std::uint8_t address, std::span<const std::uint8_t> packet);
  std::optional<std::vector<std::uint8_t>> interrupt_in(std::uint8_t address);
  void bus_reset();
  /// \brief Whether IN or OUT endpoint `address` is halted (usbdevfs: EPIPE).
  bool endpoint_halted(std::uint8_t address) const { return usb_->endpoint_halted(address); }
  /// \brief Enumerates the device as Linux does at plug-in (after the hub's
  /// kAttachDebounceUs of virtual time), leaving it configured at `address`.
  Enumeration enumerate(std::uint8_t address = 2);

  // Identity for the umockdev sysfs record --------------------------------------
  std::uint16_t vendor_id() const;
  std::uint16_t product_id() const;
  std::uint16_t bcd_device() const;
  /// \brief sysfs "descriptors": the device descriptor, then the configuration.
  std::vector<std::uint8_t> sysfs_descriptors() const;
  /// \brief The HID report descriptor (application mode; empty in the bootloader).
  std::span<const std::uint8_t> hid_report_descriptor() const;
  std::string serial() const;

  // Board side -------------------------------------------------------------------
  /// \brief One main-loop pass (HID work, bootloader entry, DFU leave).
  void poll();
  /// \brief Runs virtual time to `time_us` (slot tables, strobes, frames), then poll().
  void run_until(std::uint64_t time_us);
  void run_for(std::uint64_t duration_us);

  SimPort& port() { return port_; }
  SimFlash& flash() { return flash_; }
  /// \brief The board's security floor (kept across resets and power cycles).
  SimSecurityFloor& security_floor() { return security_floor_; }
  SimUsbController& usb() { return *usb_; }
  const SimBoardConfig& config() const { return config_; }
  /// \brief Application mode's objects (nullptr in the bootloader).
  Controller* controller() { return controller_.get(); }
  usb::ApplicationUsb* application() { return application_.get(); }
  /// \brief Bootloader mode's objects (nullptr in the application).
  usb::BootloaderUsb* bootloader() { return bootloader_.get(); }
  /// \brief Resets made by the board itself (detach, leave), not by reset() calls.
  int self_resets() const { return self_resets_; }

 private:
  void boot(bool dfu_requested, ResetCause cause = ResetCause::kPowerOn);
  void teardown();
  /// After a host-side call: main loop, then a reset if the image asked for one.
  void after_host_call();

  SimBoardConfig config_;
  SimPort port_;
  SimFlash flash_;
  SimSecurityFloor security_floor_;
  BoardMode mode_ = BoardMode::kBootloader;
  std::uint32_t epoch_ = 0;
  int self_resets_ = 0;
  int bootloader_entries_seen_ = 0;
  std::function<void(BoardMode, std::uint32_t)> reenumerate_callback_;
  BootRecord boot_record_{};  ///< no-init SRAM: invalid after a power-on
  bool recovery_pin_ = false;
  BootConfirmation confirmation_;

  std::array<std::uint8_t, 18> device_descriptor_{};
  std::unique_ptr<SimUsbController> usb_;
  std::unique_ptr<Controller> controller_;
  std::unique_ptr<CommandHandler> handler_;
  std::unique_ptr<usb::ApplicationUsb> application_;
  std::unique_ptr<usb::BootloaderUsb> bootloader_;
};

}  // namespace flutterscan::firmware::sim
