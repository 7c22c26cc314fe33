#pragma once
// Host-compilable arithmetic of the OTG_FS device driver (RM0090 chapter 34):
// the FIFO RAM plan, endpoint control and transfer-size register values, the
// receive-status word, and the turnaround time for the AHB clock. The driver
// (otg_fs_device.cpp) uses these; firmware_usb_test checks them.

#include <cstdint>

#include "flutterscan/firmware/stm32f4/registers.hpp"
#include "flutterscan/firmware/usb/usb_types.hpp"

namespace flutterscan::firmware::stm32f4::otg_layout {

/// \brief Where each FIFO lives in the 320-word FIFO RAM (RM0090 34.11).
struct FifoPlan {
  std::uint32_t rx_words;   ///< shared RX FIFO: SETUPs, OUT packets, status entries
  std::uint32_t tx0_words;  ///< EP0 IN
  std::uint32_t tx1_words;  ///< EP1 IN (the HID reports)
  constexpr std::uint32_t tx0_start() const { return rx_words; }
  constexpr std::uint32_t tx1_start() const { return rx_words + tx0_words; }
  constexpr std::uint32_t total() const { return rx_words + tx0_words + tx1_words; }
};

/// RX: RM0090 34.11.3 suggests (4 * control endpoints + 6) + 2 * (largest
/// packet / 4 + 1) + 1 words for status and SETUPs = 10 + 34 + 1; 128 leaves
/// room for several 64-byte packets. TX: two 64-byte packets each.
inline constexpr FifoPlan kFifoPlan{128, 32, 32};
static_assert(kFifoPlan.total() <= reg::otg::kFifoRamWords);
static_assert(kFifoPlan.tx0_words >= 16 && kFifoPlan.tx0_words <= 256,
              "TX FIFO depth: 16..256 words (RM0090 34.16.2)");

/// \brief An OTG_FS_DIEPTXFx / DIEPTXF0 value: depth in 31:16, start address in 15:0 (words).
constexpr std::uint32_t tx_fifo_value(std::uint32_t start_words, std::uint32_t depth_words) {
  return depth_words << 16 | start_words;
}

/// \brief GUSBCFG.TRDT for an AHB clock of `hclk_hz` (RM0090 table "TRDT values"
/// for the full-speed core): the slower the AHB, the more PHY clocks to wait.
constexpr std::uint32_t turnaround_time(std::uint32_t hclk_hz) {
  constexpr std::uint32_t kMHz = 1'000'000;
  if (hclk_hz >= 32 * kMHz) return 0x6;
  if (hclk_hz >= 27'500'000) return 0x7;
  if (hclk_hz >= 24 * kMHz) return 0x8;
  if (hclk_hz >= 21'800'000) return 0x9;
  if (hclk_hz >= 20 * kMHz) return 0xA;
  if (hclk_hz >= 18'500'000) return 0xB;
  if (hclk_hz >= 17'200'000) return 0xC;
  if (hclk_hz >= 16 * kMHz) return 0xD;
  if (hclk_hz >= 15 * kMHz) return 0xE;
  return 0xF;  // 14.2 MHz is the minimum for full speed
}

/// \brief DOEPTSIZ0 for EP0 OUT: up to 3 back-to-back SETUPs and one packet of `bytes`.
constexpr std::uint32_t ep0_out_transfer_size(std::uint32_t bytes) {
  return 3u << reg::otg::kTsizStupcntShift | 1u << reg::otg::kTsizPktcntShift | (bytes & 0x7F);
}

/// \brief DIEPTSIZx / DOEPTSIZx for one packet of `bytes` (0 for a zero-length packet).
constexpr std::uint32_t one_packet_transfer_size(std::uint32_t bytes) {
  return 1u << reg::otg::kTsizPktcntShift | (bytes & 0x7FFFF);
}

/// \brief DIEPCTLx / DOEPCTLx of an opened non-control endpoint: max packet,
/// type, TX FIFO `tx_fifo` (IN), active, DATA0, NAK set.
constexpr std::uint32_t endpoint_control(usb::EndpointType type, std::uint16_t max_packet,
                                         int tx_fifo) {
  return (max_packet & reg::otg::kEpctlMpsizMask) | reg::otg::kEpctlUsbaep |
         static_cast<std::uint32_t>(type) << reg::otg::kEpctlEptypShift |
         static_cast<std::uint32_t>(tx_fifo) << reg::otg::kEpctlTxfnumShift |
         reg::otg::kEpctlSd0pid | reg::otg::kEpctlSnak;
}

/// \brief One entry of the receive status queue (GRXSTSP).
struct RxStatus {
  int endpoint;
  std::uint32_t bytes;
  std::uint32_t packet_status;  ///< kPkts*
};

constexpr RxStatus decode_rx_status(std::uint32_t word) {
  return {static_cast<int>(word & reg::otg::kRxstsEpnumMask),
          (word & reg::otg::kRxstsBcntMask) >> reg::otg::kRxstsBcntShift,
          (word & reg::otg::kRxstsPktstsMask) >> reg::otg::kRxstsPktstsShift};
}

/// \brief 32-bit FIFO words holding `bytes`.
constexpr std::uint32_t fifo_words(std::uint32_t bytes) {
  return (bytes + 3) / 4;
}

}  // namespace flutterscan::firmware::stm32f4::otg_layout
