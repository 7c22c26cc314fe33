#pragma once
// The LED controller without hardware: the firmware's own core (Controller and
// CommandHandler) on the simulation port, behind a mutex so a host reader
// thread, the command path and a simulated camera can use it at once. Used by
// `flutterscan demo`, simulated sessions, `--device sim` and the tests.
//
// The USB side is modelled as the HID interface is: request reports go in,
// reply reports and exposure-event reports come out of one IN queue. The
// physical side is the camera's strobe (expose), the encoder and the LED bank,
// all on the sim port's virtual microsecond clock, which moves only when told.

#include <array>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "flutterscan/common/protocol.hpp"
#include "flutterscan/firmware/command_handler.hpp"
#include "flutterscan/firmware/controller.hpp"
#include "flutterscan/firmware/settings.hpp"
#include "flutterscan/firmware/sim/sim_port.hpp"

namespace flutterscan::device {

/// \brief One 64-byte HID report.
using Report = std::array<std::uint8_t, protocol::kReportSize>;

/// \brief One LED bank write: time, BSRR word, GPIO levels and LEDs on after it.
using LedTransition = firmware::sim::LedTransition;

/// \brief Serial number of a virtual controller unless another is given (24 hex digits,
/// like the STM32's unique ID).
inline constexpr const char* kVirtualSerial = "51A1A7ED0000000000000001";

/// \brief The product board as GetInfo describes it (three LEDs on pins 0..2, board
/// id kBoardIdStm32f405) with the firmware version of this build.
firmware::BoardConfig default_virtual_board();

/// \brief Virtual time from the controller's boot to the first request a host can
/// send it (USB debounce, reset and enumeration on a real board).
inline constexpr std::uint64_t kBootToFirstRequestUs = 500'000;

/// \brief How a virtual controller is built.
struct VirtualControllerOptions {
  std::string serial = kVirtualSerial;
  /// Board facts GetInfo reports (LED pins, board id, firmware version).
  firmware::BoardConfig board = default_virtual_board();
  /// Protocol major GetInfo reports (to test the host's refusal of another major).
  std::uint8_t reported_protocol_major = protocol::kProtocolMajor;
  /// Contents of the config flash page at power-on (empty: erased), e.g. saved
  /// by an earlier run with flash_page_contents().
  std::vector<std::uint8_t> initial_flash_page;
};

/// \brief The firmware core on the sim port; every method is thread-safe.
class VirtualController {
 public:
  explicit VirtualController(VirtualControllerOptions options = {});
  ~VirtualController();
  VirtualController(const VirtualController&) = delete;
  VirtualController& operator=(const VirtualController&) = delete;

  // USB side ----------------------------------------------------------------
  /// \brief Handles one request report and returns its reply directly (not via
  /// the IN queue). Unresponsive or unplugged: the request is dropped and the
  /// returned report is all zero (command 0 is never a reply).
  Report request(std::span<const std::uint8_t> report);
  /// \brief The next exposure event as a report, if the controller queued one.
  std::optional<Report> next_event_report();

  /// \brief Interrupt OUT: handles `report`, its reply goes to the IN queue.
  /// False if the device is unplugged (the write fails); true but no reply when
  /// it is unresponsive.
  bool write_report(std::span<const std::uint8_t> report);
  /// \brief Interrupt IN: a queued reply, else the next event report, else nothing.
  std::optional<Report> read_report();

  // Physical side -------------------------------------------------------------
  /// \brief One camera exposure: the strobe is active from now for `exposure_us`;
  /// runs the virtual clock through the pulse and until the sequence has ended.
  void expose(std::uint32_t exposure_us);
  /// \brief Turns the encoder by `counts` now.
  void add_encoder_counts(std::int32_t counts);
  /// \brief (Added for the sim camera, host/capture/sim_camera.cpp.) From now on the
  /// encoder turns at `counts_per_second` as the virtual clock runs, so an
  /// exposure's encoder_delta is the belt's motion during it.
  void set_encoder_velocity(std::int32_t counts_per_second);
  /// \brief Runs the virtual clock `duration_us` forward (frame ticks in master
  /// and free-run modes happen here).
  void advance_us(std::uint64_t duration_us);
  /// \brief Controller clock (restarts at 0 after a re-plug, like a power cycle;
  /// kBootToFirstRequestUs have passed when a host can talk to it).
  std::uint64_t now_us() const;
  /// \brief Every LED bank write since the last call, oldest first.
  std::vector<LedTransition> take_led_transitions();
  /// \brief LEDs on now (bit k = LED k).
  std::uint8_t led_mask() const;

  // Identity and faults -------------------------------------------------------
  const std::string& serial_number() const { return options_.serial; }
  /// \brief Board facts (GetInfo's source).
  const firmware::BoardConfig& board() const { return options_.board; }
  /// \brief false: requests are swallowed without a reply (a hung firmware).
  void set_responsive(bool responsive);
  /// \brief true: requests are handled but their replies held back until
  /// hold_replies(false) (a slow link: late replies for the host to discard).
  void hold_replies(bool hold);
  /// \brief Pulls the cable: writes fail, every LED goes dark, queued reports are lost.
  void unplug();
  /// \brief Plugs it back in: the controller boots afresh (power cycle) with the
  /// configuration saved in its flash page.
  void plug_in();
  bool plugged_in() const;
  /// \brief Whether the firmware reset into its DFU bootloader (EnterBootloader);
  /// the application interface is then gone until plug_in().
  bool in_bootloader() const;
  /// \brief The config flash page now (what SaveConfig wrote).
  std::vector<std::uint8_t> flash_page_contents() const;

 private:
  void boot_locked();
  void poll_locked();
  Report handle_locked(std::span<const std::uint8_t> report);

  VirtualControllerOptions options_;
  mutable std::mutex mutex_;
  std::unique_ptr<firmware::sim::SimPort> port_;
  std::unique_ptr<firmware::Controller> controller_;
  std::unique_ptr<firmware::CommandHandler> handler_;
  std::deque<Report> replies_;
  std::deque<Report> held_replies_;
  bool holding_replies_ = false;
  std::vector<LedTransition> earlier_transitions_;  ///< from before a re-plug
  bool responsive_ = true;
  bool plugged_in_ = true;
  bool in_bootloader_ = false;
};

}  // namespace flutterscan::device
