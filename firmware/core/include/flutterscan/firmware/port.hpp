#pragma once
// The Port seam: everything the controller core needs from the hardware, and
// the callbacks the hardware makes into the core. port/stm32f4 implements it on
// the chip (TIM1/TIM8 update -> DMA2 -> GPIOx_BSRR for slots), port/qemu on
// QEMU's netduinoplus2, port/sim on a virtual clock for tests.
// Freestanding C++20: no heap, no exceptions, no RTTI.

#include <cstddef>
#include <cstdint>
#include <span>

namespace flutterscan::firmware {

/// \brief Config pages: SaveConfig rewrites the older one (config_store.hpp).
inline constexpr int kConfigCopies = 2;

/// \brief Result of a port operation.
enum class PortStatus : std::uint8_t { kOk, kError };

/// \brief Why the controller last started.
enum class ResetCause : std::uint8_t { kPowerOn, kWatchdog, kSoftware };

/// \brief A pre-armed slot table that a trigger edge started in hardware.
struct PrearmStart {
  bool started = false;       ///< an edge started it (it plays, or played)
  std::uint64_t time_us = 0;  ///< when it started, or later (never earlier)
  bool edge_pending = false;  ///< the callback of the edge that started it is still to come
};

/// \brief What the hardware reports to the core. On the MCU these run in
/// interrupt context; the core keeps them short and allocation-free.
class PortListener {
 public:
  /// \brief The camera strobe input became active (`active`) or inactive at `time_us`.
  virtual void on_strobe_edge(bool active, std::uint64_t time_us) = 0;
  /// \brief The slot timer wrote the table's last word (all LEDs off) at `time_us`.
  virtual void on_slot_table_done(std::uint64_t time_us) = 0;
  /// \brief The frame timer (master and free-run modes) started a frame at `time_us`.
  virtual void on_frame_tick(std::uint64_t time_us) = 0;

 protected:
  ~PortListener() = default;
};

/// \brief The hardware behind the controller core.
class Port {
 public:
  /// \brief Where strobe, slot-table and frame callbacks go (nullptr: nowhere).
  virtual void set_listener(PortListener* listener) = 0;

  /// \brief Monotonic microseconds since start.
  virtual std::uint64_t now_us() = 0;

  /// \brief Writes one BSRR word to the LED GPIO port now.
  virtual void write_led_bank(std::uint32_t bsrr) = 0;
  /// \brief Sets LED `led`'s brightness (PWM on its driver's dimming input), 0..1000.
  virtual void set_led_brightness(int led, std::uint16_t permille) = 0;

  /// \brief Starts the slot timer: writes words[i] to the LED bank at now + i *
  /// slot_time_us, then calls on_slot_table_done. `words` must stay unchanged until then.
  virtual PortStatus start_slot_table(std::span<const std::uint32_t> words,
                                      std::uint32_t slot_time_us) = 0;
  /// \brief Stops the slot timer without writing further words or calling back;
  /// also withdraws a pre-armed table.
  virtual void stop_slot_table() = 0;
  /// \brief Pre-arms `words` at `slot_time_us`: the next trigger edge (the
  /// strobe's active edge in slave mode, a frame tick while the frame timer
  /// runs) starts it in hardware, before the edge's callback runs, as
  /// start_slot_table would at that edge. The controller pre-arms only a table
  /// the guard has accepted for any start from now on. kError: not supported
  /// (the controller then starts every exposure from the edge's callback).
  /// `words` must stay unchanged until the table is done or withdrawn.
  virtual PortStatus prearm_slot_table(std::span<const std::uint32_t> words,
                                       std::uint32_t slot_time_us) = 0;
  /// \brief Withdraws the pre-armed table. If an edge has already started it,
  /// it keeps playing (and will call on_slot_table_done) and the result says so.
  virtual PrearmStart cancel_prearm() = 0;

  /// \brief Sets the strobe input's polarity (edges are reported as active/inactive).
  virtual void configure_strobe_input(bool active_low) = 0;
  /// \brief Starts frames every period_us from now (first tick now); with a
  /// non-zero trigger_pulse_us also drives the camera trigger output high for
  /// that long at every tick (master mode).
  virtual PortStatus start_frame_timer(std::uint32_t period_us, std::uint32_t trigger_pulse_us) = 0;
  /// \brief Stops the frame timer and leaves the trigger output low.
  virtual void stop_frame_timer() = 0;

  /// \brief The quadrature encoder's count (wraps in two's complement).
  virtual std::int32_t encoder_count() = 0;

  /// \brief Bytes in each of the two config pages (separately erasable flash
  /// sectors, kConfigCopies of them, so a power loss while one is rewritten
  /// leaves the other intact).
  virtual std::size_t config_page_size() = 0;
  /// \brief Reads `out.size()` bytes of config page `copy` from `offset`.
  virtual PortStatus read_config_page(int copy, std::size_t offset,
                                      std::span<std::uint8_t> out) = 0;
  /// \brief Erases config page `copy` (every byte 0xFF).
  virtual PortStatus erase_config_page(int copy) = 0;
  /// \brief Programs `data` into the (erased) config page `copy` at `offset`, in address order.
  virtual PortStatus write_config_page(int copy, std::size_t offset,
                                       std::span<const std::uint8_t> data) = 0;

  /// \brief Restarts the watchdog's countdown.
  virtual void kick_watchdog() = 0;
  /// \brief Why the controller last started.
  virtual ResetCause reset_cause() = 0;
  /// \brief Resets into the DFU bootloader (does not return on hardware).
  virtual void enter_bootloader() = 0;

 protected:
  ~Port() = default;
};

}  // namespace flutterscan::firmware
