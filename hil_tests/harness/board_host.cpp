#include "board_host.hpp"

#include <algorithm>
#include <cstddef>
#include <cstdio>

#include "flutterscan/common/protocol.hpp"
#include "flutterscan/firmware/usb/dfu.hpp"

namespace flutterscan::hil {

namespace {

using firmware::sim::BoardMode;
namespace fsim = firmware::sim;

/// Longest virtual-time step of one service-loop tick (ticks come every 0.5 ms).
constexpr std::uint64_t kMaxStepUs = 1000;

const char* mode_text(BoardMode mode) {
  return mode == BoardMode::kApplication ? "application" : "bootloader";
}

std::string hex(std::span<const std::uint8_t> bytes) {
  std::string out;
  char b[3];
  for (std::uint8_t v : bytes) {
    std::snprintf(b, sizeof b, "%02x", v);
    out += b;
  }
  return out;
}

const char* dfu_request_name(std::uint8_t request) {
  static constexpr const char* kNames[] = {"DETACH",    "DNLOAD",   "UPLOAD", "GETSTATUS",
                                           "CLRSTATUS", "GETSTATE", "ABORT"};
  return request < std::size(kNames) ? kNames[request] : "?";
}

}  // namespace

BoardHost::BoardHost(const fsim::SimBoardConfig& config, std::span<const std::uint8_t> image,
                     Scenario scenario)
    : board_(config, image), scenario_(scenario), start_(std::chrono::steady_clock::now()) {
  if (scenario_.recovery_pin_boots > 0) {
    // The SimBoard powered on as it was built; power it on again with the pin held.
    board_.set_recovery_pin(true);
    board_.reset(false);
    event(std::string("power on in ") + mode_text(board_.mode()) + " mode (recovery pin held)");
    recovery_pin_boots_left_ = scenario_.recovery_pin_boots;
    booted();  // the power-on is the first boot
  } else {
    event(std::string("power on in ") + mode_text(board_.mode()) + " mode");
  }
  board_.on_reenumerate([this](fsim::BoardMode, std::uint32_t) { booted(); });
}

void BoardHost::booted() {
  if (recovery_pin_boots_left_ == 0 || --recovery_pin_boots_left_ > 0) return;
  board_.set_recovery_pin(false);
  event("recovery pin released");
}

std::uint64_t BoardHost::real_now_us() const {
  return static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::microseconds>(
                                        std::chrono::steady_clock::now() - start_)
                                        .count());
}

void BoardHost::event(const std::string& what) {
  events_.push_back({{"t_us", board_.port().now_us()}, {"what", what}});
}

bool BoardHost::present_locked(int generation) const {
  return plugged_in_ && generation == enumerated_generation_ &&
         static_cast<std::uint32_t>(generation) == board_.epoch();
}

bool BoardHost::present(int generation) {
  std::lock_guard lock(mutex_);
  return present_locked(generation);
}

// ---------------------------------------------------------------------------
// Host side

std::optional<ControlOutcome> BoardHost::control(int generation,
                                                 std::span<const std::uint8_t, 8> setup,
                                                 std::span<const std::uint8_t> out_data) {
  std::lock_guard lock(mutex_);
  if (!present_locked(generation)) return std::nullopt;
  const bool dfu_dnload = board_.mode() == BoardMode::kBootloader && setup[0] == 0x21 &&
                          setup[1] == static_cast<std::uint8_t>(firmware::usb::DfuRequest::kDnload);
  const int block = setup[2] | setup[3] << 8;
  if (dfu_dnload && scenario_.unplug_at_block >= 0 && block == scenario_.unplug_at_block &&
      out_data.size() > 0) {
    scenario_.unplug_at_block = -1;
    unplug_locked(("power lost at DFU block " + std::to_string(block)).c_str());
    return std::nullopt;
  }
  const fsim::ControlResult r = board_.control_transfer(setup, out_data);
  ControlOutcome outcome{r.stalled, r.data};
  note_control(setup, out_data, outcome);
  return outcome;
}

OutResult BoardHost::interrupt_out(int generation, std::uint8_t address,
                                   std::span<const std::uint8_t> packet) {
  std::lock_guard lock(mutex_);
  if (!present_locked(generation)) return OutResult::kGone;
  if (unresponsive_) {
    // A hung main loop: the peripheral takes one packet into its buffer, then NAKs.
    if (swallowed_one_) return OutResult::kNak;
    swallowed_one_ = true;
    out_reports_.push_back(
        {{"t_us", board_.port().now_us()}, {"hex", hex(packet)}, {"swallowed", true}});
    return OutResult::kTaken;
  }
  if (scenario_.unresponsive_after >= 0 && requests_taken_ >= scenario_.unresponsive_after) {
    unresponsive_ = true;
    event("device stops answering (after " + std::to_string(requests_taken_) + " requests)");
    swallowed_one_ = true;
    out_reports_.push_back(
        {{"t_us", board_.port().now_us()}, {"hex", hex(packet)}, {"swallowed", true}});
    return OutResult::kTaken;
  }
  const fsim::OutResult r = board_.interrupt_out(address, packet);
  switch (r) {
    case fsim::OutResult::kAck:
      note_out_report(packet);
      return OutResult::kTaken;
    case fsim::OutResult::kNak:
      return OutResult::kNak;
    case fsim::OutResult::kStall:
    case fsim::OutResult::kNoEndpoint:
      // usbdevfs would report EPIPE; hidraw's writer sees an I/O error. Neither
      // happens with a configured HID interface; count it as taken and record it.
      out_reports_.push_back(
          {{"t_us", board_.port().now_us()}, {"hex", hex(packet)}, {"refused", true}});
      return OutResult::kTaken;
  }
  return OutResult::kNak;
}

std::optional<std::optional<std::vector<std::uint8_t>>> BoardHost::interrupt_in(
    int generation, std::uint8_t address) {
  std::lock_guard lock(mutex_);
  if (!present_locked(generation)) return std::nullopt;
  if (unresponsive_) return std::optional<std::vector<std::uint8_t>>{};
  auto packet = board_.interrupt_in(address);
  if (packet) note_in_report(*packet);
  return packet;
}

bool BoardHost::reset(int generation) {
  std::lock_guard lock(mutex_);
  if (!present_locked(generation)) return false;
  event("USBDEVFS_RESET");
  board_.bus_reset();
  if (static_cast<std::uint32_t>(generation) != board_.epoch()) return false;  // re-enumerates
  // The kernel re-enumerates in place: address and configuration as before.
  board_.enumerate(enumerated_address_);
  return static_cast<std::uint32_t>(generation) == board_.epoch();
}

// ---------------------------------------------------------------------------
// Records

void BoardHost::note_control(std::span<const std::uint8_t, 8> setup,
                             std::span<const std::uint8_t> out, const ControlOutcome& outcome) {
  // Class requests to an interface: DFU (both modes) and HID.
  if ((setup[0] & 0x60) != 0x20) return;
  const bool dfu =
      board_.mode() == BoardMode::kBootloader || (setup[4] == firmware::usb::kDfuRuntimeInterface);
  if (!dfu) return;
  nlohmann::json r{{"t_us", board_.port().now_us()},        {"mode", mode_text(board_.mode())},
                   {"request", dfu_request_name(setup[1])}, {"value", setup[2] | setup[3] << 8},
                   {"length", setup[6] | setup[7] << 8},    {"stalled", outcome.stalled}};
  if (!out.empty()) r["out_bytes"] = out.size();
  if (setup[1] == static_cast<std::uint8_t>(firmware::usb::DfuRequest::kGetStatus) &&
      outcome.in_data.size() >= 5) {
    r["status"] = outcome.in_data[0];
    r["state"] = outcome.in_data[4];
  }
  dfu_requests_.push_back(std::move(r));
}

void BoardHost::note_out_report(std::span<const std::uint8_t> packet) {
  ++requests_taken_;
  nlohmann::json r{{"t_us", board_.port().now_us()}, {"bytes", packet.size()}};
  if (!packet.empty()) r["command"] = packet[0];
  if (packet.size() > 1) r["sequence"] = packet[1];
  r["hex"] = hex(packet);
  out_reports_.push_back(std::move(r));
  if (!packet.empty() && packet[0] == static_cast<std::uint8_t>(protocol::Command::kArm))
    arm_sent_ = true;
  if (scenario_.unplug_after >= 0 && requests_taken_ >= scenario_.unplug_after) {
    scenario_.unplug_after = -1;
    unplug_locked(("unplugged after " + std::to_string(requests_taken_) + " requests").c_str());
  }
}

void BoardHost::note_in_report(std::vector<std::uint8_t>& packet) {
  if (packet.size() < protocol::kHeaderSize) return;
  const std::uint8_t command = packet[0];
  const std::uint8_t status = packet[3];
  if (scenario_.protocol_major >= 0 &&
      command == static_cast<std::uint8_t>(protocol::Command::kGetInfo) &&
      status == static_cast<std::uint8_t>(protocol::Status::kOk) &&
      packet.size() >= protocol::kHeaderSize + sizeof(protocol::InfoReply))
    packet[protocol::kHeaderSize + offsetof(protocol::InfoReply, protocol_major)] =
        static_cast<std::uint8_t>(scenario_.protocol_major);
  nlohmann::json r{{"t_us", board_.port().now_us()},
                   {"command", command},
                   {"sequence", packet[1]},
                   {"status", status}};
  if (command == static_cast<std::uint8_t>(protocol::Command::kExposureEvent) &&
      packet.size() >= protocol::kHeaderSize + sizeof(protocol::ExposureEvent)) {
    protocol::ExposureEvent e{};
    std::memcpy(&e, packet.data() + protocol::kHeaderSize, sizeof e);
    r["frame_counter"] = e.frame_counter;
    r["slot_time_us"] = e.slot_time_us;
    r["start_time_us"] = e.start_time_us;
    r["encoder_delta"] = e.encoder_delta;
    r["code_id"] = e.code_id;
    r["slot_count"] = e.slot_count;
    r["flags"] = e.flags;
    ++events_delivered_;
    if (scenario_.unplug_after_events >= 0 && events_delivered_ >= scenario_.unplug_after_events) {
      scenario_.unplug_after_events = -1;
      unplug_locked(
          ("unplugged after " + std::to_string(events_delivered_) + " exposure events").c_str());
    }
  }
  in_reports_.push_back(std::move(r));
  if (arm_sent_ && !strobes_scheduled_ && scenario_.strobes_after_arm > 0 &&
      command == static_cast<std::uint8_t>(protocol::Command::kArm) &&
      status == static_cast<std::uint8_t>(protocol::Status::kOk))
    schedule_strobes();
}

void BoardHost::schedule_strobes() {
  strobes_scheduled_ = true;
  // The first strobe one period after the Arm reply reached the host.
  const std::uint64_t first = board_.port().now_us() + scenario_.strobe_period_us;
  for (int i = 0; i < scenario_.strobes_after_arm; ++i) {
    const std::uint64_t t = first + static_cast<std::uint64_t>(i) * scenario_.strobe_period_us;
    board_.port().inject_strobe(t, scenario_.strobe_width_us);
    stimuli_.push_back({t, Stimulus::Kind::kStrobe, i});
    if (scenario_.encoder_in_exposure != 0)
      stimuli_.push_back({t + 5, Stimulus::Kind::kEncoder, scenario_.encoder_in_exposure + i});
    if (scenario_.encoder_between != 0)
      stimuli_.push_back({t + scenario_.strobe_period_us * 9 / 10, Stimulus::Kind::kEncoder,
                          scenario_.encoder_between});
  }
  std::stable_sort(stimuli_.begin() + static_cast<std::ptrdiff_t>(next_stimulus_), stimuli_.end(),
                   [](const Stimulus& a, const Stimulus& b) { return a.time_us < b.time_us; });
  event("scheduled " + std::to_string(scenario_.strobes_after_arm) + " strobes");
}

void BoardHost::unplug_locked(const char* why) {
  plugged_in_ = false;
  event(why);
  events_.back()["led_mask_at_unplug"] = board_.port().led_mask();
  if (scenario_.replug_after_ms >= 0)
    replug_at_ =
        std::chrono::steady_clock::now() + std::chrono::milliseconds(scenario_.replug_after_ms);
}

// ---------------------------------------------------------------------------
// Service loop

void BoardHost::tick() {
  std::lock_guard lock(mutex_);
  if (!plugged_in_) {
    if (replug_at_ && std::chrono::steady_clock::now() >= *replug_at_) {
      replug_at_.reset();
      plugged_in_ = true;
      unresponsive_ = false;
      board_.reset(false);  // power cycle: the boot decision picks the image
      event(std::string("plugged back in: ") + mode_text(board_.mode()) + " mode");
    }
    return;
  }
  // The board's clock follows real time, but at most kMaxStepUs per tick: if the
  // harness was not scheduled for a while, virtual time slows down instead of
  // jumping, so stimuli never bunch up (the host gets its usual time to read).
  const std::uint64_t board_now = board_.port().now_us();
  const std::uint64_t now = std::clamp(real_now_us(), board_now, board_now + kMaxStepUs);
  while (next_stimulus_ < stimuli_.size() && stimuli_[next_stimulus_].time_us <= now) {
    const Stimulus& s = stimuli_[next_stimulus_++];
    board_.run_until(s.time_us);
    if (s.kind == Stimulus::Kind::kStrobe) {
      strobes_.push_back(
          {{"index", s.value}, {"start_us", s.time_us}, {"width_us", scenario_.strobe_width_us}});
    } else {
      board_.port().add_encoder_counts(s.value);
      if (!strobes_.empty() && s.time_us - strobes_.back()["start_us"].get<std::uint64_t>() < 100)
        strobes_.back()["encoder_counts"] = s.value;
    }
  }
  board_.run_until(now);
}

void BoardHost::power_cycle(bool dfu_requested) {
  std::lock_guard lock(mutex_);
  board_.reset(dfu_requested);
  event(std::string("reset: ") + mode_text(board_.mode()) + " mode");
}

int BoardHost::hang_before_usb(int max_resets) {
  std::lock_guard lock(mutex_);
  int resets = 0;
  while (board_.mode() == firmware::sim::BoardMode::kApplication && resets < max_resets) {
    board_.watchdog_reset();
    ++resets;
    event(std::string("watchdog reset: ") + mode_text(board_.mode()) + " mode");
  }
  return resets;
}

std::optional<int> BoardHost::wanted_generation() {
  std::lock_guard lock(mutex_);
  if (!plugged_in_) return std::nullopt;
  return static_cast<int>(board_.epoch());
}

EnumeratedDevice BoardHost::enumerate(std::uint8_t address, const std::string& devnode) {
  std::lock_guard lock(mutex_);
  EnumeratedDevice d;
  d.enumeration = board_.enumerate(address);
  enumerated_address_ = address;
  d.generation = static_cast<int>(board_.epoch());
  d.mode = board_.mode();
  d.vendor_id = board_.vendor_id();
  d.product_id = board_.product_id();
  d.bcd_device = board_.bcd_device();
  d.sysfs_descriptors = board_.sysfs_descriptors();
  d.hid_report_descriptor = d.enumeration.hid_report_descriptor;
  enumerated_generation_ = d.enumeration.ok ? d.generation : -1;
  enumerations_.push_back({{"t_us", board_.port().now_us()},
                           {"mode", mode_text(d.mode)},
                           {"generation", d.generation},
                           {"devnode", devnode},
                           {"product_id", d.product_id},
                           {"serial", d.enumeration.serial},
                           {"ok", d.enumeration.ok},
                           {"error", d.enumeration.error}});
  return d;
}

void BoardHost::removed(int generation) {
  std::lock_guard lock(mutex_);
  if (enumerated_generation_ == generation) enumerated_generation_ = -1;
}

nlohmann::json BoardHost::records() {
  std::lock_guard lock(mutex_);
  nlohmann::json leds = nlohmann::json::array();
  for (const auto& t : board_.port().led_transitions()) leds.push_back({t.time_us, t.led_mask});
  nlohmann::json j;
  j["led_transitions"] = std::move(leds);
  j["out_reports"] = out_reports_;
  j["in_reports"] = in_reports_;
  j["dfu_requests"] = dfu_requests_;
  j["strobes"] = strobes_;
  j["events"] = events_;
  j["enumerations"] = enumerations_;
  const auto region = board_.config().region;
  j["final"] = {{"mode", mode_text(board_.mode())},
                {"plugged_in", plugged_in_},
                {"led_mask", board_.port().led_mask()},
                {"clock_us", board_.port().now_us()},
                {"epoch", board_.epoch()},
                {"serial", board_.serial()},
                {"bcd_device", board_.bcd_device()}};
  const auto app = board_.flash().read(region.load_address, 64);
  j["final"]["app_region_head"] = hex(app);
  int bootloader_sector_writes = 0;
  for (int s = 0; s < static_cast<int>(board_.flash().layout().sectors.size()); ++s)
    if (board_.flash().layout().sectors[static_cast<std::size_t>(s)].base < region.load_address)
      bootloader_sector_writes += board_.flash().erase_count(s) + board_.flash().program_count(s);
  j["final"]["writes_below_app_region"] = bootloader_sector_writes;
  return j;
}

}  // namespace flutterscan::hil
