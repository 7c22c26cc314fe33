#pragma once
// The byte format of a command_handler_fuzz input, shared by the fuzz target
// (which reads it) and the seed generator (which writes it).
//
// An input is one board byte followed by operations, each an op byte and its
// arguments. A missing argument byte reads as 0, so every byte string is a
// valid input; the fuzzer's mutations stay meaningful. Times are `Time`:
// a little-endian u16 and a shift byte (value = u16 << (shift % 8)), so exact
// small values and seconds are both a few bytes away.
//
// The USB ops (kSetup and after) go through the USB device core on a
// SimUsbController: the application's (HID + DFU runtime around the same
// Controller) and, for the kDfu* ops, a bootloader's (DFU mode over a SimFlash).
// kRawReport/kReport still go straight into the CommandHandler, where their
// replies are checked in full. kEp0Packets plays control transfers one
// endpoint-0 transaction at a time (per-packet data stages, the status stage,
// a SETUP interrupting a data stage, SETUPs back to back).

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace flutterscan::firmware::fuzz {

/// \brief Board byte: bits 0-1 LED count - 1, bits 2-3 pin layout, bits 4-5 default guard,
/// bit 6 the product port's timing (interrupt latency, every request handled under the
/// interrupt lock), bit 7 its size (latency 3 or 25 us, lock 10 or 150 us per request).
inline constexpr std::uint8_t kBoardTiming = 0x40;
inline constexpr std::uint8_t kBoardSlowInterrupts = 0x80;
inline constexpr int kPinLayouts = 4;

/// \brief Operations (op byte % kOpCount).
enum class Op : std::uint8_t {
  kRawReport = 0,      ///< length byte (% 66: 0..65), then that many bytes as they are
  kReport = 1,         ///< command (1 + byte % 13), sequence, then exactly the command's
                       ///< request payload, framed by encode_raw into a 64-byte report
  kUploadCode = 2,     ///< code id, led count, total slots (u16, 1 + v % 256), flags byte
                       ///< (bit 0 one-of-N, bit 7: masks unmasked and flags raw), masks:
                       ///< one byte per slot; sent as SetCode chunks of 52 slots
  kStrobes = 3,        ///< count (1 + byte % 8), first at now + Time, period Time, width Time
  kAdvance = 4,        ///< Time: run the virtual clock
  kEncoder = 5,        ///< byte (bit 0: 0 add counts, 1 set velocity), i32 little-endian
  kPoll = 6,           ///< Controller::poll (watchdog, bootloader entry)
  kReadEvents = 7,     ///< up to 1 + byte % 20 exposure event reports
  kUsbReset = 8,       ///< Controller::on_usb_reset
  kPortFault = 9,      ///< Controller::on_port_fault
  kPortFailures = 10,  ///< byte: bit 0 slot timer fails, bit 1 flash fails
  kReboot = 11,        ///< reset cause (byte % 3), then a new Controller on the same port
  kFlashPoke = 12,     ///< u16 offset into the config image, byte: one flash byte overwritten
  kSetup = 13,         ///< 8 SETUP bytes, then min(wLength, 1024) OUT data bytes (OUT requests)
  kHidOut = 14,        ///< length byte (% 66), then that many bytes to interrupt OUT 0x01
  kHidIn = 15,         ///< up to 1 + byte % 8 packets read from interrupt IN 0x81
  kBusReset = 16,      ///< USB bus reset
  kEnumerate = 17,     ///< bus reset, SET_ADDRESS (1 + byte % 127), SET_CONFIGURATION 1
  kDfuSetup = 18,      ///< as kSetup, to the bootloader's DFU mode device
  kDfuDownload = 19,   ///< seed byte, size u16, byte: bit 0 wrong board, bit 1 bad CRC,
                       ///< bit 2 skip a block, bit 3 no GETSTATUS; dfu-util's download
  kEp0Packets = 20,    ///< byte: bit 0 the bootloader's DFU mode device (else the
                       ///< application's); count (1 + byte % 24) endpoint-0 transactions
                       ///< of the packet-level path, each a kind byte % 3: 0 SETUP (8
                       ///< bytes), 1 OUT packet (length byte % 65, then that many bytes),
                       ///< 2 IN packet. A transfer may span ops; any SETUP aborts it.
  kCount = 21,
};

inline constexpr std::uint8_t kOpCount = static_cast<std::uint8_t>(Op::kCount);

/// \brief Builds an input (seed generator and tests).
class InputWriter {
 public:
  explicit InputWriter(std::uint8_t board) { bytes_.push_back(board); }

  InputWriter& op(Op op) {
    bytes_.push_back(static_cast<std::uint8_t>(op));
    return *this;
  }
  InputWriter& u8(std::uint8_t v) {
    bytes_.push_back(v);
    return *this;
  }
  InputWriter& u16(std::uint16_t v) {
    bytes_.push_back(static_cast<std::uint8_t>(v & 0xFFu));
    bytes_.push_back(static_cast<std::uint8_t>(v >> 8));
    return *this;
  }
  InputWriter& i32(std::int32_t v) {
    const auto u = static_cast<std::uint32_t>(v);
    for (int i = 0; i < 4; ++i) bytes_.push_back(static_cast<std::uint8_t>(u >> (8 * i)));
    return *this;
  }
  /// \brief A Time argument: the nearest representable value at or below `us`.
  InputWriter& time(std::uint64_t us) {
    std::uint8_t shift = 0;
    while ((us >> shift) > 0xFFFFu && shift < 7) ++shift;
    const std::uint64_t v = us >> shift;
    return u16(static_cast<std::uint16_t>(v > 0xFFFFu ? 0xFFFFu : v)).u8(shift);
  }
  InputWriter& bytes(std::span<const std::uint8_t> b) {
    bytes_.insert(bytes_.end(), b.begin(), b.end());
    return *this;
  }

  // Whole operations.
  InputWriter& raw_report(std::span<const std::uint8_t> report) {
    return op(Op::kRawReport).u8(static_cast<std::uint8_t>(report.size())).bytes(report);
  }
  InputWriter& advance(std::uint64_t us) { return op(Op::kAdvance).time(us); }
  InputWriter& strobes(std::uint8_t count, std::uint64_t delay_us, std::uint64_t period_us,
                       std::uint64_t width_us) {
    return op(Op::kStrobes)
        .u8(static_cast<std::uint8_t>(count - 1))
        .time(delay_us)
        .time(period_us)
        .time(width_us);
  }
  InputWriter& read_events(std::uint8_t count) {
    return op(Op::kReadEvents).u8(static_cast<std::uint8_t>(count - 1));
  }
  InputWriter& setup(std::uint8_t type, std::uint8_t request, std::uint16_t value,
                     std::uint16_t index, std::uint16_t length) {
    return op(Op::kSetup).u8(type).u8(request).u16(value).u16(index).u16(length);
  }
  InputWriter& hid_out(std::span<const std::uint8_t> report) {
    return op(Op::kHidOut).u8(static_cast<std::uint8_t>(report.size())).bytes(report);
  }
  InputWriter& hid_in(std::uint8_t count) {
    return op(Op::kHidIn).u8(static_cast<std::uint8_t>(count - 1));
  }
  InputWriter& enumerate() { return op(Op::kEnumerate).u8(1); }

  const std::vector<std::uint8_t>& data() const { return bytes_; }

 private:
  std::vector<std::uint8_t> bytes_;
};

}  // namespace flutterscan::firmware::fuzz
