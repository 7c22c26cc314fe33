#pragma once
// The USB protocol between the host and the LED controller: one header compiled
// by both sides, never a hand copy. docs/protocol.md describes every
// message byte by byte.
//
// Transport: HID reports of 64 bytes (interrupt OUT for requests, interrupt IN
// for replies and exposure events). Every report starts with a 4-byte header
// (command, sequence, payload length, status) followed by at most 60 payload
// bytes; the rest of the report is padding.
//
// Wire layout: every struct below is made of fixed-width fields placed at their
// natural alignment with explicit reserved bytes, so it has no padding (checked
// by static_assert on sizeof, offsetof and has_unique_object_representations)
// and its in-memory image on a little-endian machine (the Cortex-M4 and x86-64
// both are) is its wire image. Multi-byte fields are little-endian.
//
// Compatibility: command numbers, status codes, flag bits and feature bits are
// never reused or renumbered; retired ones are reserved. A new field goes into
// reserved bytes (which a sender must set to zero and older firmware
// rejects when non-zero) or into a new command. Incompatible changes bump
// kProtocolMajor; compatible ones bump kProtocolMinor.
// Freestanding C++20: no heap, no exceptions, no RTTI.

#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <type_traits>

#include "flutterscan/common/led_code.hpp"
#include "flutterscan/common/result.hpp"
#include "flutterscan/common/sequencer.hpp"

namespace flutterscan::protocol {

static_assert(std::endian::native == std::endian::little,
              "the wire structs are little-endian images of memory");

// ---------------------------------------------------------------------------
// Versions and USB identity (the one place these numbers live)

/// Incompatible protocol changes bump the major; the host refuses another major.
inline constexpr std::uint8_t kProtocolMajor = 1;
/// Compatible additions bump the minor; any minor works with the same major.
inline constexpr std::uint8_t kProtocolMinor = 1;

/// pid.codes (https://pid.codes), the open-source USB vendor ID.
inline constexpr std::uint16_t kUsbVendorId = 0x1209;
/// pid.codes test PID for the application (HID + DFU runtime). Test PIDs must not
/// ship: replace with the assigned PID here, and only here.
inline constexpr std::uint16_t kUsbProductIdApplication = 0x0001;
/// pid.codes test PID for the bootloader (DFU mode), replaced together with the above.
inline constexpr std::uint16_t kUsbProductIdBootloader = 0x0002;

// ---------------------------------------------------------------------------
// Framing

/// Bytes in every HID report, both directions.
inline constexpr std::size_t kReportSize = 64;
/// Bytes of the header at the start of every report.
inline constexpr std::size_t kHeaderSize = 4;
/// Largest payload after the header.
inline constexpr std::size_t kMaxPayloadSize = kReportSize - kHeaderSize;

/// Code table slots on the controller (code ids 0..kMaxCodes-1).
inline constexpr std::uint8_t kMaxCodes = 8;
/// "No code" where a code id is reported.
inline constexpr std::uint8_t kNoCode = 0xFF;
/// Slot masks carried by one SetCode chunk (a 52-slot code fits one chunk).
inline constexpr std::size_t kSlotsPerCodeChunk = 52;
/// Longest code, slots.
inline constexpr int kMaxCodeSlots = flutterscan::kMaxSlots;
/// Most LEDs a code or a board can have (array sizes below).
inline constexpr int kMaxCodeLeds = flutterscan::kMaxLeds;
/// Shortest and longest slot time, microseconds (1 us steps).
inline constexpr std::uint32_t kMinSlotTimeUs = flutterscan::kMinSlotTimeUs;
inline constexpr std::uint32_t kMaxSlotTimeUs = flutterscan::kMaxSlotTimeUs;
/// Frame period range for master and free-run modes, microseconds (1 kHz .. 0.1 Hz).
inline constexpr std::uint32_t kMinFramePeriodUs = 1'000;
inline constexpr std::uint32_t kMaxFramePeriodUs = 10'000'000;
/// Brightness full scale (per mille of the LED's rated current).
inline constexpr std::uint16_t kBrightnessFullScale = 1000;
/// Duty-cycle full scale for the thermal guard (per mille).
inline constexpr std::uint16_t kDutyFullScale = 1000;
/// Longest continuous on-time the guard can be set to, microseconds
/// (a whole 256-slot exposure at the longest slot time).
inline constexpr std::uint32_t kMaxGuardOnTimeUs = kMaxCodeSlots * kMaxSlotTimeUs;
/// Argument of EnterBootloader ("DFU!" little-endian): guards against stray reports.
inline constexpr std::uint32_t kEnterBootloaderMagic = 0x21554644;

/// \brief Command numbers. Never reuse or renumber: retire a command by
/// reserving its number. 0x00 is never a command; 0x80..0xFF are messages the
/// controller sends on its own (events).
enum class Command : std::uint8_t {
  kGetInfo = 0x01,          ///< versions, identity, features, limits
  kSetCode = 0x02,          ///< upload one chunk of a code into a code slot
  kSelectCode = 0x03,       ///< make a stored code the active one (next exposure)
  kSetTiming = 0x04,        ///< slot time, frame period, slot-time source
  kSetMode = 0x05,          ///< sync mode and strobe polarity
  kSetBrightness = 0x06,    ///< per-LED brightness (PWM)
  kArm = 0x07,              ///< start reacting to triggers / generating frames
  kDisarm = 0x08,           ///< stop, all LEDs off; also clears a fault
  kGetStatus = 0x09,        ///< state, counters, last fault
  kSelfTest = 0x0A,         ///< light each LED in turn once
  kSaveConfig = 0x0B,       ///< store the configuration in flash (CRC-checked)
  kEnterBootloader = 0x0C,  ///< reboot into the DFU bootloader
  kSetGuard = 0x0D,         ///< thermal guard limits per LED
  kExposureEvent = 0x80,    ///< controller -> host after every exposure
};

/// \brief Whether `value` is a command number the host may send.
constexpr bool is_request_command(std::uint8_t value) {
  return value >= static_cast<std::uint8_t>(Command::kGetInfo) &&
         value <= static_cast<std::uint8_t>(Command::kSetGuard);
}

/// \brief Status of a reply. Never reuse or renumber.
enum class Status : std::uint8_t {
  kOk = 0,
  kUnknownCommand = 1,   ///< command number not known to this firmware
  kBadLength = 2,        ///< report or payload length wrong for the command
  kBadHeader = 3,        ///< reserved header byte not zero
  kOutOfRange = 4,       ///< an argument outside its documented range (or reserved byte set)
  kBadState = 5,         ///< not allowed in the controller's current state
  kNoSuchCode = 6,       ///< the code slot is empty
  kBadCode = 7,          ///< the uploaded code is not valid (LED beyond the count, one-of-N broken)
  kOutOfOrder = 8,       ///< a SetCode chunk that does not continue the upload in progress
  kGuardLimit = 9,       ///< the thermal guard forbids this code/timing
  kTimingConflict = 10,  ///< frame period shorter than the exposure
  kFlashError = 11,      ///< flash erase, write or verify failed
  kBusy = 12,            ///< a self test is running
  kHardwareError = 13,   ///< the port refused (e.g. timer could not start)
  kAboveCeiling = 14,    ///< above the board's compiled LED ceiling (protocol 1.1)
};

/// \brief A short English text for a status (for the host's messages).
constexpr const char* status_text(Status status) {
  switch (status) {
    case Status::kOk:
      return "ok";
    case Status::kUnknownCommand:
      return "unknown command";
    case Status::kBadLength:
      return "wrong message length";
    case Status::kBadHeader:
      return "reserved header byte is not zero";
    case Status::kOutOfRange:
      return "argument out of range";
    case Status::kBadState:
      return "not allowed in the controller's current state";
    case Status::kNoSuchCode:
      return "no code stored under that id";
    case Status::kBadCode:
      return "invalid code";
    case Status::kOutOfOrder:
      return "code chunk out of order";
    case Status::kGuardLimit:
      return "refused by the LED thermal guard";
    case Status::kTimingConflict:
      return "frame period shorter than the exposure";
    case Status::kFlashError:
      return "flash error";
    case Status::kBusy:
      return "busy (self test running)";
    case Status::kHardwareError:
      return "hardware error";
    case Status::kAboveCeiling:
      return "above the LED ceiling compiled into the firmware";
  }
  return "unknown status";
}

/// \brief Controller states (GetStatus).
enum class ControllerState : std::uint8_t { kIdle = 0, kArmed = 1, kExposing = 2, kFault = 3 };

/// \brief The state as people read it (GetStatus's `state` byte): "idle", "armed",
/// "exposing", "fault", or "unknown" for a number the protocol does not define.
constexpr const char* controller_state_name(std::uint8_t state) {
  switch (static_cast<ControllerState>(state)) {
    case ControllerState::kIdle:
      return "idle";
    case ControllerState::kArmed:
      return "armed";
    case ControllerState::kExposing:
      return "exposing";
    case ControllerState::kFault:
      return "fault";
  }
  return "unknown";
}

/// \brief How exposures are started.
enum class SyncMode : std::uint8_t {
  kSlave = 0,    ///< the camera's strobe output starts each sequence
  kMaster = 1,   ///< the controller triggers the camera every frame period
  kFreeRun = 2,  ///< sequences every frame period, no camera signal
};

/// \brief The sync mode as people read it (GetStatus's `sync_mode` byte, the
/// words of docs/protocol.md): "slave", "master", "free-run", or "unknown" for
/// a number the protocol does not define.
constexpr const char* sync_mode_name(std::uint8_t mode) {
  switch (static_cast<SyncMode>(mode)) {
    case SyncMode::kSlave:
      return "slave";
    case SyncMode::kMaster:
      return "master";
    case SyncMode::kFreeRun:
      return "free-run";
  }
  return "unknown";
}

/// \brief Where the slot time comes from.
enum class SlotTimeSource : std::uint8_t {
  kFixed = 0,           ///< the slot time set by SetTiming
  kFollowExposure = 1,  ///< slave mode: previous strobe pulse width / code length
};

/// \brief Why the controller last faulted or reset (GetStatus).
enum class FaultCode : std::uint8_t {
  kNone = 0,
  kWatchdogReset = 1,  ///< the last reset was the watchdog's
  kSlotTimer = 2,      ///< the slot timer could not be started
  kPort = 3,           ///< the hardware layer reported a fault
};

/// Feature bits of GetInfo. Never reuse a bit.
inline constexpr std::uint32_t kFeatureSlaveSync = 1u << 0;
inline constexpr std::uint32_t kFeatureMasterSync = 1u << 1;
inline constexpr std::uint32_t kFeatureFreeRun = 1u << 2;
inline constexpr std::uint32_t kFeatureFollowExposure = 1u << 3;
inline constexpr std::uint32_t kFeatureEncoder = 1u << 4;
inline constexpr std::uint32_t kFeatureBrightness = 1u << 5;
inline constexpr std::uint32_t kFeatureThermalGuard = 1u << 6;
inline constexpr std::uint32_t kFeatureConfigFlash = 1u << 7;
inline constexpr std::uint32_t kFeatureDfu = 1u << 8;

/// Exposure event flag bits. Never reuse a bit.
inline constexpr std::uint16_t kEventMissedTrigger = 1u << 0;  ///< a trigger came while exposing
inline constexpr std::uint16_t kEventOverrun = 1u << 1;        ///< sequence outlasted the exposure
inline constexpr std::uint16_t kEventCodeSwitched = 1u << 2;   ///< first exposure with a new code
inline constexpr std::uint16_t kEventGuardHit = 1u << 3;       ///< guard refused: LEDs stayed off
inline constexpr std::uint16_t kEventSlotTimeClamped = 1u
                                                       << 4;  ///< followed slot time out of range

/// Status flag bits of GetStatus. Never reuse a bit.
inline constexpr std::uint8_t kStatusConfigFromFlash = 1u << 0;  ///< config loaded from flash
inline constexpr std::uint8_t kStatusConfigCorrupt = 1u << 1;    ///< flash config rejected (CRC...)
inline constexpr std::uint8_t kStatusSelfTestRunning = 1u << 2;
inline constexpr std::uint8_t kStatusUploadInProgress = 1u
                                                        << 3;  ///< a SetCode upload is unfinished

/// SetCode flag bits.
inline constexpr std::uint8_t kCodeFlagOneOfN = 1u << 0;  ///< reject unless one LED per slot

// ---------------------------------------------------------------------------
// Header

/// \brief The first 4 bytes of every report.
struct MessageHeader {
  std::uint8_t command;         ///< Command (replies echo the request's)
  std::uint8_t sequence;        ///< chosen by the host, echoed in the reply
  std::uint8_t payload_length;  ///< payload bytes after the header (0..60)
  std::uint8_t status;          ///< requests: 0 (reserved); replies: Status
};

// ---------------------------------------------------------------------------
// Payloads. Requests without arguments (GetInfo, Arm, Disarm, GetStatus,
// SaveConfig) carry an empty payload; replies without data likewise.

/// \brief GetInfo reply.
struct InfoReply {
  std::uint8_t protocol_major;
  std::uint8_t protocol_minor;
  std::uint8_t firmware_major;
  std::uint8_t firmware_minor;
  std::uint8_t firmware_patch;
  std::uint8_t led_count;  ///< LEDs on this board (code bits usable)
  std::uint8_t max_codes;  ///< code slots (ids 0..max_codes-1)
  std::uint8_t reserved0;
  std::uint32_t build_id;  ///< e.g. the first 8 hex digits of the source revision
  std::uint32_t features;  ///< kFeature* bits
  std::uint16_t board_id;
  std::uint16_t max_slots;  ///< longest code
  std::uint32_t min_slot_time_us;
  std::uint32_t max_slot_time_us;
};

/// \brief SetCode request: one chunk of a code upload. Chunks go in order; a chunk
/// with first_slot 0 starts a new upload; the chunk that reaches total_slots
/// validates the code and stores it under code_id.
struct SetCodeRequest {
  std::uint8_t code_id;                                ///< 0..kMaxCodes-1
  std::uint8_t led_count;                              ///< LEDs of the code, 1..board LED count
  std::uint16_t total_slots;                           ///< 1..256, the same in every chunk
  std::uint16_t first_slot;                            ///< slot index of masks[0]
  std::uint8_t slot_count;                             ///< masks used in this chunk, 1..52
  std::uint8_t flags;                                  ///< kCodeFlag* bits
  std::array<std::uint8_t, kSlotsPerCodeChunk> masks;  ///< per-slot LED bit masks
};

/// \brief SetCode reply.
struct SetCodeReply {
  std::uint16_t slots_received;  ///< slots of the upload stored so far
  std::uint8_t complete;         ///< 1 once the code is stored under its id
  std::uint8_t reserved0;
};

/// \brief SelectCode request.
struct SelectCodeRequest {
  std::uint8_t code_id;
  std::array<std::uint8_t, 3> reserved;
};

/// \brief SelectCode reply: the code exposing now and the one taking over next.
struct SelectCodeReply {
  std::uint8_t active_code_id;   ///< kNoCode if none
  std::uint8_t pending_code_id;  ///< kNoCode if no switch is pending
  std::array<std::uint8_t, 2> reserved;
};

/// \brief SetTiming request.
struct SetTimingRequest {
  std::uint32_t slot_time_us;  ///< kMinSlotTimeUs..kMaxSlotTimeUs
  std::uint32_t
      frame_period_us;  ///< master/free-run: kMinFramePeriodUs..kMaxFramePeriodUs; 0 = unset
  std::uint8_t slot_time_source;  ///< SlotTimeSource
  std::array<std::uint8_t, 3> reserved;
};

/// \brief SetMode request.
struct SetModeRequest {
  std::uint8_t sync_mode;          ///< SyncMode
  std::uint8_t strobe_active_low;  ///< 0: strobe active high; 1: active low
  std::array<std::uint8_t, 2> reserved;
};

/// \brief SetBrightness request.
struct SetBrightnessRequest {
  std::array<std::uint16_t, kMaxCodeLeds>
      permille;  ///< per LED, 0..1000; entries past the LED count ignored
};

/// \brief SetGuard request: thermal limits per LED.
struct SetGuardRequest {
  std::array<std::uint32_t, kMaxCodeLeds> max_on_time_us;     ///< 1..kMaxGuardOnTimeUs
  std::array<std::uint16_t, kMaxCodeLeds> max_duty_permille;  ///< 1..1000
};

/// \brief SelfTest request: each LED on for step_time_us, one after the other.
struct SelfTestRequest {
  std::uint32_t step_time_us;  ///< kMinSlotTimeUs..kMaxSlotTimeUs
};

/// \brief SelfTest reply.
struct SelfTestReply {
  std::uint8_t leds_stepped;
  std::array<std::uint8_t, 3> reserved;
  std::uint32_t duration_us;  ///< when the last LED goes off, from now
};

/// \brief SaveConfig reply.
struct SaveConfigReply {
  std::uint32_t bytes_written;
  std::uint32_t crc32;
};

/// \brief EnterBootloader request.
struct EnterBootloaderRequest {
  std::uint32_t magic;  ///< kEnterBootloaderMagic
};

/// \brief GetStatus reply.
struct StatusReply {
  std::uint8_t state;            ///< ControllerState
  std::uint8_t sync_mode;        ///< SyncMode
  std::uint8_t active_code_id;   ///< kNoCode if none
  std::uint8_t pending_code_id;  ///< kNoCode if none
  std::uint8_t last_fault;       ///< FaultCode
  std::uint8_t flags;            ///< kStatus* bits
  std::uint8_t codes_stored;     ///< bit i set: code id i holds a code
  std::uint8_t reserved0;
  std::uint32_t slot_time_us;   ///< slot time of the next exposure
  std::uint32_t frame_counter;  ///< exposures started since Arm
  std::uint32_t missed_triggers;
  std::uint32_t overruns;
  std::uint32_t guard_hits;
  std::uint32_t events_dropped;  ///< events lost because the host did not read them
  std::uint64_t uptime_us;
};

/// \brief ExposureEvent (controller -> host, after every exposure).
struct ExposureEvent {
  std::uint32_t frame_counter;   ///< 1 for the first exposure after Arm
  std::uint32_t slot_time_us;    ///< slot time used
  std::uint64_t start_time_us;   ///< controller clock at the start of slot 0
  std::int32_t encoder_delta;    ///< encoder counts from slot 0 to the end of the last slot
  std::uint32_t pulse_width_us;  ///< slave: measured strobe pulse width (0 if not ended yet)
  std::uint16_t flags;           ///< kEvent* bits
  std::uint8_t code_id;
  std::uint8_t reserved0;
  std::uint16_t slot_count;  ///< code length L
  std::uint16_t reserved1;
};

// ---------------------------------------------------------------------------
// Layout checks: any change here is a protocol change (docs/protocol.md).

/// \brief A struct whose memory image is its wire image: trivially copyable, no padding.
template <typename T>
concept WireStruct = std::is_trivially_copyable_v<T> && std::has_unique_object_representations_v<T>;

static_assert(WireStruct<MessageHeader> && sizeof(MessageHeader) == kHeaderSize);
static_assert(offsetof(MessageHeader, sequence) == 1 &&
              offsetof(MessageHeader, payload_length) == 2 && offsetof(MessageHeader, status) == 3);

static_assert(WireStruct<InfoReply> && sizeof(InfoReply) == 28);
static_assert(offsetof(InfoReply, led_count) == 5 && offsetof(InfoReply, max_codes) == 6 &&
              offsetof(InfoReply, build_id) == 8 && offsetof(InfoReply, features) == 12 &&
              offsetof(InfoReply, board_id) == 16 && offsetof(InfoReply, max_slots) == 18 &&
              offsetof(InfoReply, min_slot_time_us) == 20 &&
              offsetof(InfoReply, max_slot_time_us) == 24);

static_assert(WireStruct<SetCodeRequest> && sizeof(SetCodeRequest) == kMaxPayloadSize);
static_assert(offsetof(SetCodeRequest, led_count) == 1 &&
              offsetof(SetCodeRequest, total_slots) == 2 &&
              offsetof(SetCodeRequest, first_slot) == 4 &&
              offsetof(SetCodeRequest, slot_count) == 6 && offsetof(SetCodeRequest, flags) == 7 &&
              offsetof(SetCodeRequest, masks) == 8);
static_assert(WireStruct<SetCodeReply> && sizeof(SetCodeReply) == 4);
static_assert(offsetof(SetCodeReply, complete) == 2);

static_assert(WireStruct<SelectCodeRequest> && sizeof(SelectCodeRequest) == 4);
static_assert(WireStruct<SelectCodeReply> && sizeof(SelectCodeReply) == 4);
static_assert(offsetof(SelectCodeReply, pending_code_id) == 1);

static_assert(WireStruct<SetTimingRequest> && sizeof(SetTimingRequest) == 12);
static_assert(offsetof(SetTimingRequest, frame_period_us) == 4 &&
              offsetof(SetTimingRequest, slot_time_source) == 8);

static_assert(WireStruct<SetModeRequest> && sizeof(SetModeRequest) == 4);
static_assert(offsetof(SetModeRequest, strobe_active_low) == 1);

static_assert(kMaxCodeLeds == 4 && kMaxCodeSlots == 256, "the wire layout assumes these");
static_assert(WireStruct<SetBrightnessRequest> && sizeof(SetBrightnessRequest) == 8);

static_assert(WireStruct<SetGuardRequest> && sizeof(SetGuardRequest) == 24);
static_assert(offsetof(SetGuardRequest, max_duty_permille) == 16);

static_assert(WireStruct<SelfTestRequest> && sizeof(SelfTestRequest) == 4);
static_assert(WireStruct<SelfTestReply> && sizeof(SelfTestReply) == 8);
static_assert(offsetof(SelfTestReply, duration_us) == 4);

static_assert(WireStruct<SaveConfigReply> && sizeof(SaveConfigReply) == 8);
static_assert(offsetof(SaveConfigReply, crc32) == 4);

static_assert(WireStruct<EnterBootloaderRequest> && sizeof(EnterBootloaderRequest) == 4);

static_assert(WireStruct<StatusReply> && sizeof(StatusReply) == 40);
static_assert(offsetof(StatusReply, last_fault) == 4 && offsetof(StatusReply, flags) == 5 &&
              offsetof(StatusReply, codes_stored) == 6 &&
              offsetof(StatusReply, slot_time_us) == 8 &&
              offsetof(StatusReply, frame_counter) == 12 &&
              offsetof(StatusReply, missed_triggers) == 16 &&
              offsetof(StatusReply, overruns) == 20 && offsetof(StatusReply, guard_hits) == 24 &&
              offsetof(StatusReply, events_dropped) == 28 &&
              offsetof(StatusReply, uptime_us) == 32);

static_assert(WireStruct<ExposureEvent> && sizeof(ExposureEvent) == 32);
static_assert(offsetof(ExposureEvent, slot_time_us) == 4 &&
              offsetof(ExposureEvent, start_time_us) == 8 &&
              offsetof(ExposureEvent, encoder_delta) == 16 &&
              offsetof(ExposureEvent, pulse_width_us) == 20 &&
              offsetof(ExposureEvent, flags) == 24 && offsetof(ExposureEvent, code_id) == 26 &&
              offsetof(ExposureEvent, slot_count) == 28);

// ---------------------------------------------------------------------------
// Encoding and decoding. Nothing here reads or writes past the span it is given.

/// \brief A received report split into header and payload (the payload views the report).
struct MessageView {
  MessageHeader header{};
  std::span<const std::uint8_t> payload;
};

/// \brief The header of `report` as far as it goes: missing bytes read as 0.
/// Lets a reply echo command and sequence even for a malformed request.
inline MessageHeader peek_header(std::span<const std::uint8_t> report) {
  std::array<std::uint8_t, kHeaderSize> bytes{};
  for (std::size_t i = 0; i < kHeaderSize && i < report.size(); ++i) bytes[i] = report[i];
  MessageHeader header;
  std::memcpy(&header, bytes.data(), kHeaderSize);
  return header;
}

/// \brief Splits a report into header and payload. kBadLength if the report is
/// shorter than the header, longer than kReportSize, or shorter than the payload
/// length it declares; `status` is not checked (replies use it, requests need 0).
inline Result<MessageView, Status> parse_message(std::span<const std::uint8_t> report) {
  if (report.size() < kHeaderSize || report.size() > kReportSize)
    return Result<MessageView, Status>::failure(Status::kBadLength);
  MessageView view;
  view.header = peek_header(report);
  if (view.header.payload_length > report.size() - kHeaderSize)
    return Result<MessageView, Status>::failure(Status::kBadLength);
  view.payload = report.subspan(kHeaderSize, view.header.payload_length);
  return Result<MessageView, Status>::success(view);
}

/// \brief Parses a request: parse_message plus kBadHeader if the reserved status byte is set.
inline Result<MessageView, Status> parse_request(std::span<const std::uint8_t> report) {
  auto message = parse_message(report);
  if (message.ok() && message.value().header.status != 0)
    return Result<MessageView, Status>::failure(Status::kBadHeader);
  return message;
}

/// \brief The payload as a T; kBadLength unless it is exactly sizeof(T) bytes.
template <WireStruct T>
Result<T, Status> decode_payload(std::span<const std::uint8_t> payload) {
  if (payload.size() != sizeof(T)) return Result<T, Status>::failure(Status::kBadLength);
  T value;
  std::memcpy(&value, payload.data(), sizeof(T));
  return Result<T, Status>::success(value);
}

/// \brief Whether an argument-less message's payload is empty (kOk) or not (kBadLength).
inline Status expect_empty_payload(std::span<const std::uint8_t> payload) {
  return payload.empty() ? Status::kOk : Status::kBadLength;
}

/// \brief Writes a full report: header, `payload` bytes, zero padding to
/// kReportSize. Returns kReportSize, or 0 (nothing written) if `report` is
/// shorter than kReportSize or the payload longer than kMaxPayloadSize.
inline std::size_t encode_raw(std::uint8_t command, std::uint8_t sequence, Status status,
                              std::span<const std::uint8_t> payload,
                              std::span<std::uint8_t> report) {
  if (report.size() < kReportSize || payload.size() > kMaxPayloadSize) return 0;
  const MessageHeader header{command, sequence, static_cast<std::uint8_t>(payload.size()),
                             static_cast<std::uint8_t>(status)};
  std::memcpy(report.data(), &header, kHeaderSize);
  for (std::size_t i = 0; i < kMaxPayloadSize; ++i)
    report[kHeaderSize + i] = i < payload.size() ? payload[i] : std::uint8_t{0};
  return kReportSize;
}

/// \brief Writes a message whose payload is `payload` (see encode_raw).
template <WireStruct T>
std::size_t encode_message(std::uint8_t command, std::uint8_t sequence, Status status,
                           const T& payload, std::span<std::uint8_t> report) {
  static_assert(sizeof(T) <= kMaxPayloadSize, "payload does not fit a report");
  std::array<std::uint8_t, sizeof(T)> bytes;
  std::memcpy(bytes.data(), &payload, sizeof(T));
  return encode_raw(command, sequence, status, bytes, report);
}

/// \brief Writes a message without payload (see encode_raw).
inline std::size_t encode_empty(std::uint8_t command, std::uint8_t sequence, Status status,
                                std::span<std::uint8_t> report) {
  return encode_raw(command, sequence, status, {}, report);
}

/// \brief Host side: writes a request with a payload (status byte 0).
template <WireStruct T>
std::size_t encode_request(Command command, std::uint8_t sequence, const T& payload,
                           std::span<std::uint8_t> report) {
  return encode_message(static_cast<std::uint8_t>(command), sequence, Status::kOk, payload, report);
}

/// \brief Host side: writes a request without payload.
inline std::size_t encode_request(Command command, std::uint8_t sequence,
                                  std::span<std::uint8_t> report) {
  return encode_empty(static_cast<std::uint8_t>(command), sequence, Status::kOk, report);
}

}  // namespace flutterscan::protocol
