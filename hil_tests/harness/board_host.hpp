#pragma once
// BoardHost: the firmware's SimBoard (port/sim: the USB core, the controller
// or the DFU bootloader, the virtual flash) behind one lock, as the HIL
// harness serves it. It is the DevicePort of the umockdev handlers, runs the
// board's virtual clock in step with real time, plays the scenario (strobes
// and encoder counts after Arm, an unresponsive or unplugged device, another
// protocol major, an unplug in the middle of a DFU download) and records what
// happened for the test to assert on.

#include <chrono>
#include <cstdint>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "device_port.hpp"
#include "flutterscan/firmware/sim/sim_board.hpp"

namespace flutterscan::hil {

/// \brief What the harness makes the board do, beyond answering the host.
struct Scenario {
  /// Strobes started after the first successful Arm reply reaches the host.
  int strobes_after_arm = 0;
  std::uint32_t strobe_width_us = 1000;
  std::uint32_t strobe_period_us = 10000;
  /// Encoder counts added in the middle of exposure i's first slot: base + i.
  std::int32_t encoder_in_exposure = 0;
  /// Encoder counts added between exposures (must not show in any event).
  std::int32_t encoder_between = 0;
  /// After this many request reports the device stops answering (-1: never).
  int unresponsive_after = -1;
  /// After this many request reports the device is unplugged (-1: never).
  int unplug_after = -1;
  /// After this many exposure events reached the host the device is unplugged (-1: never).
  int unplug_after_events = -1;
  /// Unplug when DFU DNLOAD block N arrives (-1: never): power lost mid-flash.
  int unplug_at_block = -1;
  /// Plug back in (power cycle) this long after an unplug (-1: stay unplugged).
  int replug_after_ms = -1;
  /// GetInfo replies carry this protocol major instead (-1: the real one).
  int protocol_major = -1;
  /// The recovery pin is held at power-on and through this many boots in all
  /// (each reset after the power-on counts, those the board makes itself too),
  /// then released: as a user who keeps the button pressed until then. 0: never held.
  int recovery_pin_boots = 0;
};

/// \brief A device as enumerated, ready to be put into the testbed.
struct EnumeratedDevice {
  int generation = 0;
  firmware::sim::BoardMode mode = firmware::sim::BoardMode::kApplication;
  firmware::sim::Enumeration enumeration;
  std::uint16_t vendor_id = 0;
  std::uint16_t product_id = 0;
  std::uint16_t bcd_device = 0;
  std::vector<std::uint8_t> sysfs_descriptors;
  std::vector<std::uint8_t> hid_report_descriptor;
};

/// \brief The board, its clock, its scenario and its records.
class BoardHost final : public DevicePort {
 public:
  BoardHost(const firmware::sim::SimBoardConfig& config, std::span<const std::uint8_t> image,
            Scenario scenario);

  // DevicePort (umockdev worker thread) ------------------------------------------
  std::optional<ControlOutcome> control(int generation, std::span<const std::uint8_t, 8> setup,
                                        std::span<const std::uint8_t> out_data) override;
  OutResult interrupt_out(int generation, std::uint8_t address,
                          std::span<const std::uint8_t> packet) override;
  std::optional<std::optional<std::vector<std::uint8_t>>> interrupt_in(
      int generation, std::uint8_t address) override;
  bool reset(int generation) override;
  bool present(int generation) override;

  // Service loop (main thread) -----------------------------------------------------
  /// \brief Resets the board (power cycle; `dfu_requested`: the application's hand-off).
  void power_cycle(bool dfu_requested);
  /// \brief The image in flash hangs before it brings USB up (it never
  /// confirms itself): the watchdog resets the chip until the bootloader keeps
  /// DFU mode (boot_decision.hpp), at most `max_resets` times. Returns the resets.
  int hang_before_usb(int max_resets);
  /// \brief Runs virtual time up to real time, playing scheduled stimuli.
  void tick();
  /// \brief What the bus should hold now: nullopt if nothing (unplugged) or the
  /// board's current enumeration number.
  std::optional<int> wanted_generation();
  /// \brief Enumerates the board (as the kernel does at plug-in) for the testbed.
  EnumeratedDevice enumerate(std::uint8_t address, const std::string& devnode);
  /// \brief Notes that the testbed no longer holds enumeration `generation`.
  void removed(int generation);

  /// \brief Everything recorded, as JSON (see README.md for the fields).
  nlohmann::json records();

 private:
  struct Stimulus {
    std::uint64_t time_us;
    enum class Kind { kStrobe, kEncoder } kind;
    std::int32_t value;  ///< strobe: index; encoder: counts
  };

  std::uint64_t real_now_us() const;
  bool present_locked(int generation) const;
  void note_out_report(std::span<const std::uint8_t> packet);
  void note_in_report(std::vector<std::uint8_t>& packet);
  void note_control(std::span<const std::uint8_t, 8> setup, std::span<const std::uint8_t> out,
                    const ControlOutcome& outcome);
  void schedule_strobes();
  void unplug_locked(const char* why);
  void event(const std::string& what);
  /// After every boot: counts the boots the recovery pin is still held for.
  void booted();

  std::mutex mutex_;
  firmware::sim::SimBoard board_;
  Scenario scenario_;
  std::chrono::steady_clock::time_point start_;
  std::uint64_t clock_offset_us_ = 0;  ///< board clock = real time + offset (a reset restarts it)

  bool plugged_in_ = true;
  std::optional<std::chrono::steady_clock::time_point> replug_at_;
  int enumerated_generation_ = -1;  ///< -1: not on the bus
  std::uint8_t enumerated_address_ = 0;
  int requests_taken_ = 0;
  int events_delivered_ = 0;
  bool unresponsive_ = false;
  bool swallowed_one_ = false;
  bool strobes_scheduled_ = false;
  bool arm_sent_ = false;
  int recovery_pin_boots_left_ = 0;
  std::vector<Stimulus> stimuli_;  ///< sorted by time, consumed from the front
  std::size_t next_stimulus_ = 0;

  nlohmann::json out_reports_ = nlohmann::json::array();
  nlohmann::json in_reports_ = nlohmann::json::array();
  nlohmann::json dfu_requests_ = nlohmann::json::array();
  nlohmann::json strobes_ = nlohmann::json::array();
  nlohmann::json events_ = nlohmann::json::array();
  nlohmann::json enumerations_ = nlohmann::json::array();
};

}  // namespace flutterscan::hil
