#pragma once
// The controller: code table, state machine (idle, armed, exposing, fault) and
// the sequencing of exposures through the Port. Each command method validates
// everything before changing anything: on an error status nothing changed.
//
// Exposures: in slave mode the strobe's active edge starts one, in master and
// free-run modes the frame timer does. An exposure plays the active code's slot
// table (double-buffered: SelectCode prepares the other table, the swap happens
// at the next exposure start, never mid-sequence) and ends with every LED off;
// then an ExposureEvent is queued. With SlotTimeSource::kFollowExposure (slave
// mode) the slot time of an exposure is the previous strobe pulse width / L,
// since the current pulse's width is known only at its end.
// The thermal guard checks every exposure before it starts; an exposure it
// refuses stays dark and its event carries kEventGuardHit. Its history (when
// the last lit exposure started, when it ended, each LED's run at its end) is
// the LEDs' and outlives Arm, Disarm, faults and mode or code changes; a self
// test is an exposure like any other. Every boot, whatever the reset cause,
// starts it full: the duty period counts from boot and every LED counts as
// having been on up to its on-time ceiling until boot (the LEDs have their own
// supply, so a reset of the MCU does not cool them). Only a board that
// declares its LEDs powered with the MCU (BoardConfig::leds_powered_with_mcu)
// starts empty after a power-on reset.
// The invariant (docs/hardware.md, "Thermal guard"): for any two lit
// exposures (self tests included) starting at a < b with none between, each
// LED's energy (on-time x brightness) in the one starting at b is at most its
// duty cap times b - a, and no LED has a joined run (runs less than the
// board's minimum off-time apart are one run) longer than its max_on_time,
// across exposures too. The guard limits never exceed the board's compiled
// ceiling (BoardConfig::ceiling), nor does the brightness.
//
// On the MCU the Port callbacks run in interrupt context and the command
// methods in the main loop: the stm32f4 port must mask the strobe, frame and
// slot interrupts around command handling (not needed on the sim port).
//
// Pre-arming (issue 15, finding 3): the port can start a table on the trigger
// edge in hardware, before any callback. The controller pre-arms only the
// table of the next exposure, at its slot time, once the guard accepts it for
// every start from the moment of pre-arming on: the duty only improves with a
// later start, and a join with an LED's last run is judged at the longest gap
// that still joins, so whatever edge starts it, the guard said yes before any
// LED lit. A pre-armed table that an edge started is always
// adopted as a lit exposure, also when SelectCode or Disarm withdraws it too
// late. Otherwise the edge's callback decides and starts the table in software
// (late by the interrupt latency, never early). The controller re-decides the
// pre-arm whenever its inputs change: after each exposure, after a strobe
// pulse ends (follow-exposure slot time), on SelectCode and in poll().
// Tables are never rewritten while the DMA may read them: three of them
// (playing, pending, and the one SelectCode builds into).
// Freestanding C++20: no heap, no exceptions, no RTTI.

#include <array>
#include <cstdint>

#include "flutterscan/common/protocol.hpp"
#include "flutterscan/common/result.hpp"
#include "flutterscan/common/sequencer.hpp"
#include "flutterscan/firmware/event_queue.hpp"
#include "flutterscan/firmware/port.hpp"
#include "flutterscan/firmware/settings.hpp"

namespace flutterscan::firmware {

/// Exposure events kept until the host reads them.
inline constexpr std::size_t kEventQueueCapacity = 16;

/// \brief The LED controller core, hardware-independent.
class Controller final : public PortListener {
 public:
  /// \brief A controller driving `port` (which must outlive it) on `board`.
  Controller(Port& port, const BoardConfig& board);
  Controller(const Controller&) = delete;
  Controller& operator=(const Controller&) = delete;
  ~Controller() { port_.set_listener(nullptr); }

  /// \brief Boot: every LED off, the last reset cause noted, the configuration
  /// loaded from flash (defaults if it is missing or corrupt), brightness applied.
  void start();
  /// \brief Main-loop work: kicks the watchdog; enters the bootloader once
  /// EnterBootloader was accepted and `may_enter_bootloader` (the USB layer
  /// passes false while the reply has not been read).
  void poll(bool may_enter_bootloader = true);

  // Commands ---------------------------------------------------------------
  /// \brief GetInfo.
  protocol::InfoReply info() const;
  /// \brief SetCode: stores one chunk; the last chunk validates and stores the code.
  Result<protocol::SetCodeReply, protocol::Status> set_code_chunk(
      const protocol::SetCodeRequest& r);
  /// \brief SelectCode: idle, the code for the next Arm; armed, the code from the next exposure on.
  Result<protocol::SelectCodeReply, protocol::Status> select_code(
      const protocol::SelectCodeRequest& r);
  /// \brief SetTiming (idle only).
  protocol::Status set_timing(const protocol::SetTimingRequest& r);
  /// \brief SetMode (idle only).
  protocol::Status set_mode(const protocol::SetModeRequest& r);
  /// \brief SetBrightness: at or below the ceiling's current; lowering in any
  /// state, raising only while nothing is armed or playing.
  protocol::Status set_brightness(const protocol::SetBrightnessRequest& r);
  /// \brief SetGuard (idle only; at or below the ceiling).
  protocol::Status set_guard(const protocol::SetGuardRequest& r);
  /// \brief Arm: checks code, timing and guard, then waits for triggers or starts frames.
  protocol::Status arm();
  /// \brief Disarm: stops everything, all LEDs off; leaves the fault state.
  protocol::Status disarm();
  /// \brief GetStatus.
  protocol::StatusReply status() const;
  /// \brief SelfTest (idle only): each LED on for step_time_us in turn.
  Result<protocol::SelfTestReply, protocol::Status> self_test(const protocol::SelfTestRequest& r);
  /// \brief SaveConfig (idle only).
  Result<protocol::SaveConfigReply, protocol::Status> save_config();
  /// \brief EnterBootloader: disarms; poll() then resets into the bootloader.
  protocol::Status enter_bootloader(const protocol::EnterBootloaderRequest& r);

  // Other inputs -----------------------------------------------------------
  /// \brief The USB host reset the bus: disarm, drop an unfinished code upload.
  void on_usb_reset();
  /// \brief The hardware layer detected a fault: all LEDs off, fault state.
  void on_port_fault();

  /// \brief Takes the oldest unsent exposure event; false if there is none.
  bool pop_event(protocol::ExposureEvent& out) { return events_.pop(out); }

  protocol::ControllerState state() const { return state_; }
  const ControllerSettings& settings() const { return settings_; }
  bool bootloader_requested() const { return bootloader_requested_; }

  // PortListener -----------------------------------------------------------
  void on_strobe_edge(bool active, std::uint64_t time_us) override;
  void on_slot_table_done(std::uint64_t time_us) override;
  void on_frame_tick(std::uint64_t time_us) override;

 private:
  /// One slot table: BSRR words for one code, plus what the guard needs.
  struct SlotTable {
    std::array<std::uint32_t, kMaxSlotWords> words{};
    std::uint16_t word_count = 0;
    std::uint8_t code_id = protocol::kNoCode;
    LedCode code;
    LedOnStats stats;
  };

  /// A SetCode upload in progress.
  struct CodeUpload {
    bool active = false;
    std::uint8_t code_id = 0;
    std::uint8_t led_count = 0;
    std::uint8_t flags = 0;
    std::uint16_t total_slots = 0;
    std::uint16_t received = 0;
    std::array<std::uint8_t, kMaxSlots> masks{};
  };

  bool is_armed() const {
    return state_ == protocol::ControllerState::kArmed ||
           state_ == protocol::ControllerState::kExposing;
  }
  bool uses_frame_timer() const { return settings_.mode.sync != protocol::SyncMode::kSlave; }
  /// Fills `table` for stored code `code_id` (which must be present).
  void build_table(SlotTable& table, std::uint8_t code_id) const;
  /// kOk if code `code_id` may run with the current timing (frame period, guard)
  /// and brightness.
  protocol::Status check_code_runnable(std::uint8_t code_id) const;
  void begin_exposure(std::uint64_t time_us);
  /// Pre-arms the next exposure's table if the guard accepts it from now on
  /// (withdrawing a different one first); nothing unless armed and idle between exposures.
  void update_prearm();
  /// Withdraws the pre-armed table; true if an edge had started it (then adopted).
  bool withdraw_prearm();
  /// Records the pre-armed table an edge started as the exposure in progress.
  void adopt_prearm(const PrearmStart& start);
  /// The guard's verdict on `code` (whose stats are `stats`) at `slot_time_us`
  /// for an exposure whose LEDs light at `start_us`, given the history of lit
  /// exposures; with `any_later_start`, for every start from `start_us` on
  /// (a pre-arm): a later start still within the minimum off-time of an LED's
  /// last run joins a longer gap, so the join is judged at the longest gap that joins.
  GuardVerdict guard_verdict(const LedCode& code, const LedOnStats& stats,
                             std::uint32_t slot_time_us, std::uint64_t start_us,
                             bool any_later_start = false) const;
  /// Records a lit exposure (or self test) of `code` starting at `start_us` in the guard's history.
  void record_lit_exposure(const LedCode& code, std::uint64_t start_us,
                           std::uint32_t slot_time_us);
  std::uint32_t slot_time_for_next_exposure(int code_length, std::uint16_t& flags) const;
  void queue_event(const protocol::ExposureEvent& event);
  void stop_sequencing();
  void all_leds_off();
  void apply_brightness();
  void enter_fault(protocol::FaultCode fault);

  Port& port_;
  BoardConfig board_;
  ControllerSettings settings_;
  protocol::ControllerState state_ = protocol::ControllerState::kIdle;
  protocol::FaultCode last_fault_ = protocol::FaultCode::kNone;
  std::uint8_t config_flags_ = 0;

  CodeUpload upload_;
  std::array<SlotTable, 3> tables_{};
  int playing_table_ = 0;   ///< table of the active code
  int pending_table_ = -1;  ///< table taking over at the next exposure, -1 if none
  /// The table pre-armed in the port (the next exposure's), if any.
  struct Prearm {
    bool active = false;
    int table = 0;
    std::uint32_t slot_time_us = 0;
    std::uint16_t flags = 0;
  };
  Prearm prearm_;
  /// An adopted pre-armed start whose edge callback is still to come: that
  /// callback is the exposure's own edge, not a missed trigger.
  bool adopted_edge_pending_ = false;

  // The exposure in progress (or the last one).
  std::uint64_t exposure_start_us_ = 0;
  std::int32_t encoder_at_start_ = 0;
  std::uint32_t exposure_slot_time_us_ = 0;
  std::uint16_t exposure_flags_ = 0;
  std::uint32_t exposure_pulse_width_us_ = 0;
  /// No lit exposure since a power-on reset of a board whose LEDs are powered with the MCU.
  bool cold_ = false;
  std::uint64_t previous_start_us_ = 0;  ///< start of the last lit exposure (the guard's period)
  // Per LED, its last joined run (a refused exposure stays dark): when it
  // ended and how long it was. A lit slot starting less than the minimum
  // off-time after that end joins it (the gap counts as on). Boot sets every
  // LED's run to its on-time limit, ending at boot.
  std::array<std::uint64_t, kMaxLeds> run_end_us_{};
  std::array<std::uint64_t, kMaxLeds> run_us_{};
  std::array<bool, kMaxLeds> has_run_{};  ///< false: the LED has not lit since a cold boot
  std::uint64_t lit_end_us_ = 0;    ///< when the last lit exposure's all-off word lands
  std::uint64_t lit_start_us_ = 0;  ///< start of the last lit exposure
  /// The self test's table (its own, so a self test never writes a code's table).
  std::array<std::uint32_t, kMaxLeds + 1> self_test_words_{};
  // Strobe pulse measurement (slave mode).
  bool strobe_active_ = false;
  std::uint64_t strobe_start_us_ = 0;
  std::uint32_t last_pulse_width_us_ = 0;

  std::uint32_t frame_counter_ = 0;
  std::uint32_t missed_triggers_ = 0;
  std::uint32_t overruns_ = 0;
  std::uint32_t guard_hits_ = 0;
  std::uint32_t events_dropped_ = 0;
  bool self_test_running_ = false;
  bool bootloader_requested_ = false;
  bool bootloader_entered_ = false;
  EventQueue<protocol::ExposureEvent, kEventQueueCapacity> events_;
};

}  // namespace flutterscan::firmware
