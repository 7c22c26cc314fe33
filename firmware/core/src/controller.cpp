#include "flutterscan/firmware/controller.hpp"

#include <algorithm>

#include "flutterscan/common/joined_runs.hpp"
#include "flutterscan/firmware/config_store.hpp"

namespace flutterscan::firmware {

using protocol::ControllerState;
using protocol::Status;
using protocol::SyncMode;

namespace {

std::uint32_t exposure_duration_us(int length, std::uint32_t slot_time_us) {
  return static_cast<std::uint32_t>(length) * slot_time_us;
}

}  // namespace

Controller::Controller(Port& port, const BoardConfig& board)
    : port_(port), board_(board), settings_(default_settings(board)) {
  port_.set_listener(this);
}

void Controller::start() {
  stop_sequencing();
  state_ = ControllerState::kIdle;
  if (port_.reset_cause() == ResetCause::kWatchdog)
    last_fault_ = protocol::FaultCode::kWatchdogReset;
  // Whatever the reset cause, the LEDs may have been on just before it: they
  // have their own supply, and the MCU's power-on, brown-out and pin resets
  // say nothing about them. So the duty period counts from now and every LED
  // counts as having been on up to its on-time ceiling until now (a reset
  // loop, or a host cycling the USB port, gains no duty and no on-time).
  const std::uint64_t now = port_.now_us();
  cold_ = board_.leds_powered_with_mcu && port_.reset_cause() == ResetCause::kPowerOn;
  previous_start_us_ = now;
  lit_start_us_ = now;
  lit_end_us_ = now;
  run_end_us_.fill(now);
  for (std::size_t k = 0; k < run_us_.size(); ++k) run_us_[k] = board_.ceiling.max_on_time_us[k];
  has_run_.fill(!cold_);
  const auto loaded = load_config(port_, board_);
  if (loaded.ok()) {
    settings_ = tighten_to_ceiling(loaded.value(), board_.ceiling);
    config_flags_ = protocol::kStatusConfigFromFlash;
  } else {
    settings_ = default_settings(board_);
    config_flags_ = loaded.error() == ConfigError::kEmpty ? 0 : protocol::kStatusConfigCorrupt;
  }
  apply_brightness();
}

void Controller::poll(bool may_enter_bootloader) {
  port_.kick_watchdog();
  update_prearm();  // time passed: a table the guard refused a while ago may be fine now
  if (bootloader_requested_ && !bootloader_entered_ && may_enter_bootloader) {
    bootloader_entered_ = true;
    port_.enter_bootloader();
  }
}

// ---------------------------------------------------------------------------
// Commands

protocol::InfoReply Controller::info() const {
  protocol::InfoReply reply{};
  reply.protocol_major = protocol::kProtocolMajor;
  reply.protocol_minor = protocol::kProtocolMinor;
  reply.firmware_major = board_.firmware_major;
  reply.firmware_minor = board_.firmware_minor;
  reply.firmware_patch = board_.firmware_patch;
  reply.led_count = static_cast<std::uint8_t>(board_.pins.led_count);
  reply.max_codes = protocol::kMaxCodes;
  reply.build_id = board_.build_id;
  reply.features = protocol::kFeatureSlaveSync | protocol::kFeatureMasterSync |
                   protocol::kFeatureFreeRun | protocol::kFeatureFollowExposure |
                   protocol::kFeatureEncoder | protocol::kFeatureBrightness |
                   protocol::kFeatureThermalGuard | protocol::kFeatureConfigFlash;
  reply.board_id = board_.board_id;
  reply.max_slots = static_cast<std::uint16_t>(kMaxSlots);
  reply.min_slot_time_us = protocol::kMinSlotTimeUs;
  reply.max_slot_time_us = protocol::kMaxSlotTimeUs;
  return reply;
}

Result<protocol::SetCodeReply, Status> Controller::set_code_chunk(
    const protocol::SetCodeRequest& r) {
  using Out = Result<protocol::SetCodeReply, Status>;
  if (r.code_id >= protocol::kMaxCodes || r.led_count < 1 || r.led_count > board_.pins.led_count ||
      r.total_slots < 1 || r.total_slots > kMaxSlots || r.slot_count < 1 ||
      r.slot_count > protocol::kSlotsPerCodeChunk || r.first_slot + r.slot_count > r.total_slots ||
      (r.flags & ~protocol::kCodeFlagOneOfN) != 0)
    return Out::failure(Status::kOutOfRange);
  if (is_armed() && (tables_[static_cast<std::size_t>(playing_table_)].code_id == r.code_id ||
                     (pending_table_ >= 0 &&
                      tables_[static_cast<std::size_t>(pending_table_)].code_id == r.code_id)))
    return Out::failure(Status::kBadState);  // that code is in use
  if (r.first_slot != 0) {
    const bool continues = upload_.active && upload_.code_id == r.code_id &&
                           upload_.led_count == r.led_count && upload_.flags == r.flags &&
                           upload_.total_slots == r.total_slots && upload_.received == r.first_slot;
    if (!continues) return Out::failure(Status::kOutOfOrder);
  }

  const bool last_chunk = r.first_slot + r.slot_count == r.total_slots;
  if (last_chunk) {
    // Validate the whole code before touching the upload or the table.
    std::array<std::uint8_t, kMaxSlots> masks = upload_.masks;
    for (std::size_t i = 0; i < r.slot_count; ++i) masks[r.first_slot + i] = r.masks[i];
    const CodeRule rule =
        (r.flags & protocol::kCodeFlagOneOfN) ? CodeRule::kOneOfN : CodeRule::kAnyMask;
    const auto code = LedCode::from_masks(
        std::span<const std::uint8_t>(masks.data(), r.total_slots), r.led_count, rule);
    if (!code.ok()) return Out::failure(Status::kBadCode);
    StoredCode& stored = settings_.codes[r.code_id];
    stored.present = true;
    stored.code = code.value();
    upload_.active = false;
    return Out::success({r.total_slots, 1, 0});
  }
  // A middle chunk: check its masks now so a bad digit is reported where it is.
  const auto all_leds = static_cast<std::uint8_t>((1u << r.led_count) - 1u);
  for (std::size_t i = 0; i < r.slot_count; ++i)
    if ((r.masks[i] & ~all_leds) != 0) return Out::failure(Status::kBadCode);
  if (r.first_slot == 0) {
    upload_.active = true;
    upload_.code_id = r.code_id;
    upload_.led_count = r.led_count;
    upload_.flags = r.flags;
    upload_.total_slots = r.total_slots;
    upload_.received = 0;
  }
  for (std::size_t i = 0; i < r.slot_count; ++i) upload_.masks[r.first_slot + i] = r.masks[i];
  upload_.received = static_cast<std::uint16_t>(r.first_slot + r.slot_count);
  return Out::success({upload_.received, 0, 0});
}

Status Controller::check_code_runnable(std::uint8_t code_id) const {
  const LedCode& code = settings_.codes[code_id].code;
  const TimingSettings& timing = settings_.timing;
  const std::uint32_t duration = exposure_duration_us(code.length(), timing.slot_time_us);
  if (uses_frame_timer() && (timing.frame_period_us == 0 || timing.frame_period_us < duration))
    return Status::kTimingConflict;
  const std::uint64_t period = uses_frame_timer() ? timing.frame_period_us : 0;
  const GuardVerdict verdict = check_led_guard(led_on_stats(code), timing.slot_time_us, period,
                                               settings_.guard, settings_.brightness_permille);
  if (verdict.status != GuardStatus::kOk) return Status::kGuardLimit;
  // Joined runs within the exposure (across exposures the guard judges each
  // one as it starts).
  for (int led = 0; led < code.leds(); ++led) {
    const auto k = static_cast<std::size_t>(led);
    const JoinedRuns runs =
        joined_runs(code, led, timing.slot_time_us, board_.ceiling.min_off_time_us);
    if (runs.longest_us > settings_.guard.max_on_time_us[k]) return Status::kGuardLimit;
  }
  return Status::kOk;
}

Result<protocol::SelectCodeReply, Status> Controller::select_code(
    const protocol::SelectCodeRequest& r) {
  using Out = Result<protocol::SelectCodeReply, Status>;
  if (r.code_id >= protocol::kMaxCodes || r.reserved != std::array<std::uint8_t, 3>{})
    return Out::failure(Status::kOutOfRange);
  if (!settings_.codes[r.code_id].present) return Out::failure(Status::kNoSuchCode);
  if (!is_armed()) {
    settings_.selected_code = r.code_id;
    return Out::success({r.code_id, protocol::kNoCode, {}});
  }
  const Status runnable = check_code_runnable(r.code_id);
  if (runnable != Status::kOk) return Out::failure(runnable);
  settings_.selected_code = r.code_id;
  // The pre-armed table is the old choice: withdraw it (an edge that already
  // started it came before this command: that exposure plays the old code).
  withdraw_prearm();
  const auto& playing = tables_[static_cast<std::size_t>(playing_table_)];
  if (playing.code_id == r.code_id) {
    pending_table_ = -1;  // back to the code that is playing: cancel a pending switch
  } else {
    // Build into a table neither playing nor pending: the DMA reads neither
    // the one it plays nor (pre-armed) the pending one while the CPU writes.
    int spare = 0;
    while (spare == playing_table_ || spare == pending_table_) ++spare;
    build_table(tables_[static_cast<std::size_t>(spare)], r.code_id);
    pending_table_ = spare;
  }
  const std::uint8_t pending = pending_table_ < 0 ? protocol::kNoCode : r.code_id;
  update_prearm();
  return Out::success({playing.code_id, pending, {}});
}

Status Controller::set_timing(const protocol::SetTimingRequest& r) {
  const auto timing = timing_from_request(r);
  if (!timing.ok()) return timing.error();
  if (state_ != ControllerState::kIdle && state_ != ControllerState::kFault)
    return Status::kBadState;
  if (self_test_running_) return Status::kBusy;
  settings_.timing = timing.value();
  return Status::kOk;
}

Status Controller::set_mode(const protocol::SetModeRequest& r) {
  const auto mode = mode_from_request(r);
  if (!mode.ok()) return mode.error();
  if (state_ != ControllerState::kIdle && state_ != ControllerState::kFault)
    return Status::kBadState;
  if (self_test_running_) return Status::kBusy;
  settings_.mode = mode.value();
  return Status::kOk;
}

Status Controller::set_brightness(const protocol::SetBrightnessRequest& r) {
  const Status range = check_brightness(r.permille, board_.pins.led_count);
  if (range != Status::kOk) return range;
  const Status ceiling =
      check_brightness_ceiling(r.permille, board_.ceiling, board_.pins.led_count);
  if (ceiling != Status::kOk) return ceiling;
  bool raises = false;
  for (int led = 0; led < board_.pins.led_count; ++led) {
    const auto k = static_cast<std::size_t>(led);
    if (r.permille[k] > settings_.brightness_permille[k]) raises = true;
  }
  // The guard judged the tables playing and pre-armed at the current they
  // had: more current only where nothing is armed or playing (Arm judges the
  // code at it); less current is always within what was judged.
  if (raises && is_armed()) return Status::kBadState;
  if (raises && self_test_running_) return Status::kBusy;
  settings_.brightness_permille = r.permille;
  apply_brightness();
  return Status::kOk;
}

Status Controller::set_guard(const protocol::SetGuardRequest& r) {
  GuardLimits limits;
  limits.max_on_time_us = r.max_on_time_us;
  limits.max_duty_permille = r.max_duty_permille;
  const Status range = check_guard_limits(limits, board_.pins.led_count);
  if (range != Status::kOk) return range;
  const Status ceiling = check_guard_ceiling(limits, board_.ceiling, board_.pins.led_count);
  if (ceiling != Status::kOk) return ceiling;
  if (state_ != ControllerState::kIdle && state_ != ControllerState::kFault)
    return Status::kBadState;
  if (self_test_running_) return Status::kBusy;
  settings_.guard = limits;
  return Status::kOk;
}

Status Controller::arm() {
  if (state_ != ControllerState::kIdle) return Status::kBadState;
  if (self_test_running_) return Status::kBusy;
  const std::uint8_t id = settings_.selected_code;
  if (id >= protocol::kMaxCodes || !settings_.codes[id].present) return Status::kNoSuchCode;
  const Status runnable = check_code_runnable(id);
  if (runnable != Status::kOk) return runnable;
  // The frame timer is the one step that can still fail: start it before
  // anything changes (its ticks are ignored until the state is armed; on the
  // MCU the main loop holds the interrupt lock around commands anyway).
  if (uses_frame_timer()) {
    const std::uint32_t trigger_us =
        settings_.mode.sync == SyncMode::kMaster
            ? exposure_duration_us(settings_.codes[id].code.length(), settings_.timing.slot_time_us)
            : 0;
    if (port_.start_frame_timer(settings_.timing.frame_period_us, trigger_us) != PortStatus::kOk)
      return Status::kHardwareError;
  }

  // The guard's history (last lit exposure, its end and trailing runs) stays:
  // it is the LEDs', not the arming's.
  build_table(tables_[0], id);
  playing_table_ = 0;
  pending_table_ = -1;
  frame_counter_ = 0;
  strobe_active_ = false;
  last_pulse_width_us_ = 0;
  events_.clear();
  port_.configure_strobe_input(settings_.mode.strobe_active_low);
  state_ = ControllerState::kArmed;
  update_prearm();
  return Status::kOk;
}

Status Controller::disarm() {
  stop_sequencing();
  state_ = ControllerState::kIdle;
  return Status::kOk;
}

protocol::StatusReply Controller::status() const {
  protocol::StatusReply reply{};
  reply.state = static_cast<std::uint8_t>(state_);
  reply.sync_mode = static_cast<std::uint8_t>(settings_.mode.sync);
  reply.active_code_id = is_armed() ? tables_[static_cast<std::size_t>(playing_table_)].code_id
                                    : settings_.selected_code;
  reply.pending_code_id = is_armed() && pending_table_ >= 0
                              ? tables_[static_cast<std::size_t>(pending_table_)].code_id
                              : protocol::kNoCode;
  reply.last_fault = static_cast<std::uint8_t>(last_fault_);
  reply.flags = config_flags_;
  if (self_test_running_) reply.flags |= protocol::kStatusSelfTestRunning;
  if (upload_.active) reply.flags |= protocol::kStatusUploadInProgress;
  for (std::size_t i = 0; i < settings_.codes.size(); ++i)
    if (settings_.codes[i].present) reply.codes_stored |= static_cast<std::uint8_t>(1u << i);
  reply.slot_time_us =
      state_ == ControllerState::kExposing ? exposure_slot_time_us_ : settings_.timing.slot_time_us;
  reply.frame_counter = frame_counter_;
  reply.missed_triggers = missed_triggers_;
  reply.overruns = overruns_;
  reply.guard_hits = guard_hits_;
  reply.events_dropped = events_dropped_;
  reply.uptime_us = port_.now_us();
  return reply;
}

Result<protocol::SelfTestReply, Status> Controller::self_test(const protocol::SelfTestRequest& r) {
  using Out = Result<protocol::SelfTestReply, Status>;
  if (r.step_time_us < protocol::kMinSlotTimeUs || r.step_time_us > protocol::kMaxSlotTimeUs)
    return Out::failure(Status::kOutOfRange);
  if (self_test_running_) return Out::failure(Status::kBusy);
  if (state_ != ControllerState::kIdle) return Out::failure(Status::kBadState);
  for (int led = 0; led < board_.pins.led_count; ++led)
    if (r.step_time_us > settings_.guard.max_on_time_us[static_cast<std::size_t>(led)])
      return Out::failure(Status::kGuardLimit);

  std::array<std::uint8_t, kMaxLeds> steps{};
  for (int led = 0; led < board_.pins.led_count; ++led)
    steps[static_cast<std::size_t>(led)] = static_cast<std::uint8_t>(1u << led);
  const int leds = board_.pins.led_count;
  const auto code = LedCode::from_masks(
      std::span<const std::uint8_t>(steps.data(), static_cast<std::size_t>(leds)), leds);
  if (!code.ok()) return Out::failure(Status::kHardwareError);
  // A self test lights the LEDs like an exposure: the same guard, the same history.
  const LedOnStats stats = led_on_stats(code.value());
  const std::uint64_t start = port_.now_us();
  if (guard_verdict(code.value(), stats, r.step_time_us, start).status != GuardStatus::kOk)
    return Out::failure(Status::kGuardLimit);
  const auto schedule =
      build_slot_table(code.value(), r.step_time_us, board_.pins, self_test_words_);
  if (!schedule.ok()) return Out::failure(Status::kHardwareError);
  if (port_.start_slot_table(
          std::span<const std::uint32_t>(self_test_words_.data(), schedule.value().word_count),
          r.step_time_us) != PortStatus::kOk)
    return Out::failure(Status::kHardwareError);
  record_lit_exposure(code.value(), start, r.step_time_us);
  self_test_running_ = true;
  protocol::SelfTestReply reply{};
  reply.leds_stepped = static_cast<std::uint8_t>(leds);
  reply.duration_us = schedule.value().duration_us;
  return Out::success(reply);
}

Result<protocol::SaveConfigReply, Status> Controller::save_config() {
  using Out = Result<protocol::SaveConfigReply, Status>;
  if (state_ != ControllerState::kIdle) return Out::failure(Status::kBadState);
  if (self_test_running_) return Out::failure(Status::kBusy);
  const auto saved = firmware::save_config(port_, settings_, board_);
  if (!saved.ok()) return Out::failure(saved.error());
  return Out::success({static_cast<std::uint32_t>(sizeof(ConfigImage)), saved.value()});
}

Status Controller::enter_bootloader(const protocol::EnterBootloaderRequest& r) {
  if (r.magic != protocol::kEnterBootloaderMagic) return Status::kOutOfRange;
  disarm();
  bootloader_requested_ = true;
  return Status::kOk;
}

// ---------------------------------------------------------------------------
// Other inputs

void Controller::on_usb_reset() {
  disarm();
  upload_.active = false;
}

void Controller::on_port_fault() {
  enter_fault(protocol::FaultCode::kPort);
}

// ---------------------------------------------------------------------------
// Sequencing

void Controller::on_strobe_edge(bool active, std::uint64_t time_us) {
  if (settings_.mode.sync != SyncMode::kSlave || !is_armed()) return;
  if (active) {
    strobe_active_ = true;
    strobe_start_us_ = time_us;
    begin_exposure(time_us);
    return;
  }
  if (!strobe_active_) return;  // armed mid-pulse: no start edge to measure from
  strobe_active_ = false;
  last_pulse_width_us_ = static_cast<std::uint32_t>(time_us - strobe_start_us_);
  if (state_ == ControllerState::kExposing && strobe_start_us_ == exposure_start_us_) {
    exposure_pulse_width_us_ = last_pulse_width_us_;
    // The camera stopped exposing while LEDs are still sequencing.
    exposure_flags_ |= protocol::kEventOverrun;
    ++overruns_;
  }
  update_prearm();  // the measured width sets the next slot time (follow exposure)
}

void Controller::on_frame_tick(std::uint64_t time_us) {
  if (!uses_frame_timer() || !is_armed()) return;
  begin_exposure(time_us);
}

std::uint32_t Controller::slot_time_for_next_exposure(int code_length, std::uint16_t& flags) const {
  const TimingSettings& timing = settings_.timing;
  if (settings_.mode.sync != SyncMode::kSlave ||
      timing.source != protocol::SlotTimeSource::kFollowExposure || last_pulse_width_us_ == 0)
    return timing.slot_time_us;
  std::uint32_t slot = slot_time_for_exposure(last_pulse_width_us_, code_length);
  if (slot < protocol::kMinSlotTimeUs) {
    slot = protocol::kMinSlotTimeUs;
    flags |= protocol::kEventSlotTimeClamped;
  } else if (slot > protocol::kMaxSlotTimeUs) {
    slot = protocol::kMaxSlotTimeUs;
    flags |= protocol::kEventSlotTimeClamped;
  }
  return slot;
}

void Controller::begin_exposure(std::uint64_t time_us) {
  if (state_ == ControllerState::kExposing) {
    if (adopted_edge_pending_) {
      adopted_edge_pending_ = false;  // the edge that started the adopted pre-armed table
      return;
    }
    // A trigger while the previous sequence still runs: that frame gets no light.
    ++missed_triggers_;
    exposure_flags_ |= protocol::kEventMissedTrigger;
    return;
  }
  if (state_ != ControllerState::kArmed) return;
  // Did this edge (or one whose callback is still to come) start the pre-armed table?
  if (withdraw_prearm()) return;
  // No: decide now; the LEDs light when the table starts, now (in the callback,
  // after the interrupt latency), not at the edge.
  const std::uint64_t light_us = std::max(time_us, port_.now_us());

  std::uint16_t flags = 0;
  if (pending_table_ >= 0) {
    playing_table_ = pending_table_;
    pending_table_ = -1;
    flags |= protocol::kEventCodeSwitched;
  }
  const SlotTable& table = tables_[static_cast<std::size_t>(playing_table_)];
  const int length = table.stats.length;
  const std::uint32_t slot_time = slot_time_for_next_exposure(length, flags);
  ++frame_counter_;

  exposure_start_us_ = time_us;
  exposure_slot_time_us_ = slot_time;
  exposure_pulse_width_us_ = 0;
  exposure_flags_ = flags;

  const GuardVerdict verdict = guard_verdict(table.code, table.stats, slot_time, light_us);
  if (verdict.status != GuardStatus::kOk) {
    // This exposure stays dark, but it takes no time: a trigger in the same
    // microsecond still touches the last lit exposure, so that one stays the
    // one to join (and to measure the period from). Clearing it here let a
    // second strobe edge in the microsecond of a refused one light the LEDs
    // again with no seam check (fuzz finding, crashes/guard-refused-then-same-us).
    ++guard_hits_;
    protocol::ExposureEvent event{};
    event.frame_counter = frame_counter_;
    event.slot_time_us = slot_time;
    event.start_time_us = time_us;
    event.flags = static_cast<std::uint16_t>(flags | protocol::kEventGuardHit);
    event.code_id = table.code_id;
    event.slot_count = static_cast<std::uint16_t>(length);
    queue_event(event);
    return;  // the LEDs stay off; still armed for the next exposure
  }

  encoder_at_start_ = port_.encoder_count();
  if (port_.start_slot_table(std::span<const std::uint32_t>(table.words.data(), table.word_count),
                             slot_time) != PortStatus::kOk) {
    enter_fault(protocol::FaultCode::kSlotTimer);
    return;
  }
  record_lit_exposure(table.code, light_us, slot_time);
  state_ = ControllerState::kExposing;
}

void Controller::update_prearm() {
  if (state_ != ControllerState::kArmed) return;
  const int index = pending_table_ >= 0 ? pending_table_ : playing_table_;
  const SlotTable& table = tables_[static_cast<std::size_t>(index)];
  std::uint16_t flags = 0;
  const std::uint32_t slot_time = slot_time_for_next_exposure(table.stats.length, flags);
  const bool accepted =
      guard_verdict(table.code, table.stats, slot_time, port_.now_us(), true).status ==
      GuardStatus::kOk;
  if (accepted && prearm_.active && prearm_.table == index && prearm_.slot_time_us == slot_time)
    return;
  if (withdraw_prearm()) return;  // an edge started it: now exposing
  if (!accepted) return;          // the edge's callback will decide
  if (port_.prearm_slot_table(std::span<const std::uint32_t>(table.words.data(), table.word_count),
                              slot_time) == PortStatus::kOk)
    prearm_ = {true, index, slot_time, flags};
}

bool Controller::withdraw_prearm() {
  if (!prearm_.active) return false;
  const PrearmStart start = port_.cancel_prearm();
  if (!start.started) {
    prearm_.active = false;
    return false;
  }
  adopt_prearm(start);
  return true;
}

void Controller::adopt_prearm(const PrearmStart& start) {
  const int index = prearm_.table;
  prearm_.active = false;
  std::uint16_t flags = prearm_.flags;
  if (index != playing_table_) {
    flags |= protocol::kEventCodeSwitched;
    playing_table_ = index;
  }
  if (pending_table_ == index) pending_table_ = -1;
  const SlotTable& table = tables_[static_cast<std::size_t>(index)];
  ++frame_counter_;
  exposure_start_us_ = start.time_us;
  exposure_slot_time_us_ = prearm_.slot_time_us;
  exposure_pulse_width_us_ = 0;
  exposure_flags_ = flags;
  encoder_at_start_ = port_.encoder_count();
  // The guard accepted this table for any start from the pre-arm on.
  record_lit_exposure(table.code, start.time_us, prearm_.slot_time_us);
  state_ = ControllerState::kExposing;
  adopted_edge_pending_ = start.edge_pending;
}

GuardVerdict Controller::guard_verdict(const LedCode& code, const LedOnStats& stats,
                                       std::uint32_t slot_time_us, std::uint64_t start_us,
                                       bool any_later_start) const {
  // The period since the last lit exposure began (or since boot): one the
  // guard refused lit nothing, so it neither starts a period nor ends the
  // last lit exposure. Cold LEDs (a board powering them with the MCU, after a
  // power-on reset): the first exposure's duty is judged over the frame period
  // in master and free-run, and not at all in slave mode or for a self test.
  const bool frame_timer = is_armed() && uses_frame_timer();
  const std::uint64_t period = !cold_       ? start_us - previous_start_us_
                               : frame_timer ? settings_.timing.frame_period_us
                                             : 0;
  const GuardLimits& limits = settings_.guard;
  const auto& brightness = settings_.brightness_permille;
  GuardVerdict verdict = check_led_guard(stats, slot_time_us, period, limits, brightness);
  if (verdict.status != GuardStatus::kOk) return verdict;
  // Joined runs: inside this exposure, and its first one joined to the LED's
  // last run when it starts less than the minimum off-time after that ended.
  const std::uint32_t min_off = board_.ceiling.min_off_time_us;
  for (int led = 0; led < stats.leds; ++led) {
    const auto k = static_cast<std::size_t>(led);
    const JoinedRuns runs = joined_runs(code, led, slot_time_us, min_off);
    if (!runs.lit) continue;
    if (runs.longest_us > limits.max_on_time_us[k])
      return {GuardStatus::kOnTimeTooLong, led, runs.longest_us, limits.max_on_time_us[k]};
    const std::uint64_t first_on = start_us + runs.first_on_us;
    const std::uint64_t gap = first_on > run_end_us_[k] ? first_on - run_end_us_[k] : 0;
    if (has_run_[k] && gap < min_off) {
      // A pre-armed table may start later, up to a gap of min_off - 1 that still joins.
      const std::uint64_t joined_gap = any_later_start ? min_off - 1 : gap;
      const std::uint64_t joined = run_us_[k] + joined_gap + runs.first_run_us;
      if (joined > limits.max_on_time_us[k])
        return {GuardStatus::kOnTimeTooLong, led, joined, limits.max_on_time_us[k]};
    }
  }
  // check_led_guard judges back-to-back exposures over their own duration;
  // when this one is longer than the time since the last start (a longer code
  // or slot time after a shorter one) that is more than the time it follows:
  // the energy cap holds over the time actually elapsed.
  if (cold_) return verdict;
  for (int led = 0; led < stats.leds; ++led) {
    const auto k = static_cast<std::size_t>(led);
    const std::uint64_t energy =
        static_cast<std::uint64_t>(stats.on_slots[k]) * slot_time_us * brightness[k];
    if (energy > period * limits.max_duty_permille[k]) {
      const std::uint64_t duty =
          period == 0 ? protocol::kDutyFullScale + 1 : (energy + period - 1) / period;
      return {GuardStatus::kDutyTooHigh, led, duty, limits.max_duty_permille[k]};
    }
  }
  return verdict;
}

void Controller::record_lit_exposure(const LedCode& code, std::uint64_t start_us,
                                     std::uint32_t slot_time_us) {
  const std::uint32_t min_off = board_.ceiling.min_off_time_us;
  for (int led = 0; led < code.leds(); ++led) {
    const auto k = static_cast<std::size_t>(led);
    const JoinedRuns runs = joined_runs(code, led, slot_time_us, min_off);
    if (!runs.lit) continue;  // dark the whole exposure: its last run stays
    const std::uint64_t first_on = start_us + runs.first_on_us;
    const std::uint64_t gap = first_on > run_end_us_[k] ? first_on - run_end_us_[k] : 0;
    const bool joins = has_run_[k] && gap < min_off;
    run_us_[k] = joins && runs.one_run()
                     ? run_us_[k] + gap + (runs.last_off_us - runs.first_on_us)
                     : runs.last_run_us;
    run_end_us_[k] = start_us + runs.last_off_us;
    has_run_[k] = true;
  }
  cold_ = false;
  lit_start_us_ = start_us;
  lit_end_us_ = start_us + static_cast<std::uint64_t>(code.length()) * slot_time_us;
  previous_start_us_ = start_us;
}

void Controller::on_slot_table_done(std::uint64_t) {
  if (self_test_running_) {
    self_test_running_ = false;
    return;
  }
  if (state_ != ControllerState::kExposing) return;
  const SlotTable& table = tables_[static_cast<std::size_t>(playing_table_)];
  protocol::ExposureEvent event{};
  event.frame_counter = frame_counter_;
  event.slot_time_us = exposure_slot_time_us_;
  event.start_time_us = exposure_start_us_;
  event.encoder_delta =
      static_cast<std::int32_t>(static_cast<std::uint32_t>(port_.encoder_count()) -
                                static_cast<std::uint32_t>(encoder_at_start_));
  event.pulse_width_us = exposure_pulse_width_us_;
  event.flags = exposure_flags_;
  event.code_id = table.code_id;
  event.slot_count = static_cast<std::uint16_t>(table.stats.length);
  state_ = ControllerState::kArmed;
  queue_event(event);
  update_prearm();
}

// ---------------------------------------------------------------------------
// Helpers

void Controller::build_table(SlotTable& table, std::uint8_t code_id) const {
  const LedCode& code = settings_.codes[code_id].code;
  // Codes are checked against the board's LEDs on upload and load, and the
  // slot time only matters to the timer, so this cannot fail; any valid slot
  // time will do for the table.
  const auto schedule = build_slot_table(code, protocol::kMinSlotTimeUs, board_.pins, table.words);
  table.word_count = schedule.ok() ? schedule.value().word_count : 0;
  table.code_id = code_id;
  table.code = code;
  table.stats = led_on_stats(code);
}

void Controller::queue_event(const protocol::ExposureEvent& event) {
  if (!events_.push(event)) ++events_dropped_;
}

void Controller::stop_sequencing() {
  port_.stop_frame_timer();
  // A pre-armed table an edge already started lit the LEDs: into the history
  // before it is cut.
  withdraw_prearm();
  adopted_edge_pending_ = false;
  port_.stop_slot_table();
  all_leds_off();
  self_test_running_ = false;
  pending_table_ = -1;
  strobe_active_ = false;
  // Every LED is off now. The guard's history stays; an exposure cut short
  // ends now, and each LED's run at the cut is at most the time since it
  // started plus the run it joined (bounded by the on-time limit).
  const std::uint64_t now = port_.now_us();
  if (now < lit_end_us_) {
    for (std::size_t k = 0; k < run_us_.size(); ++k) {
      run_us_[k] = (now - lit_start_us_) + settings_.guard.max_on_time_us[k];
      run_end_us_[k] = now;
      has_run_[k] = true;
    }
    lit_end_us_ = now;
  }
}

void Controller::all_leds_off() {
  port_.write_led_bank(bsrr_all_off(board_.pins));
}

void Controller::apply_brightness() {
  for (int led = 0; led < board_.pins.led_count; ++led)
    port_.set_led_brightness(led, settings_.brightness_permille[static_cast<std::size_t>(led)]);
}

void Controller::enter_fault(protocol::FaultCode fault) {
  stop_sequencing();
  state_ = ControllerState::kFault;
  last_fault_ = fault;
}

}  // namespace flutterscan::firmware
