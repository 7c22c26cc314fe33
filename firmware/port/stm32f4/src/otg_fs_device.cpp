// OTG_FS device driver, written from RM0090 chapter 34 (34.17.1 core
// initialization, 34.17.3 device initialization, 34.17.5 device programming
// model: endpoint initialization on USB reset and on enumeration completion,
// packet read from the RX FIFO, IN data transfers).

#include "flutterscan/firmware/stm32f4/otg_fs_device.hpp"

#include <algorithm>
#include <cstring>

#include "flutterscan/firmware/stm32f4/registers.hpp"

namespace flutterscan::firmware::stm32f4 {

namespace {

namespace otg = reg::otg;
using otg_layout::kFifoPlan;

/// Bounded polls of a core flag (the core answers within a few AHB cycles; a
/// core that never does is dead, and the bound keeps the watchdog in charge).
constexpr std::uint32_t kCorePolls = 200'000;

bool wait_bits(std::uintptr_t address, std::uint32_t mask, bool set) {
  for (std::uint32_t i = 0; i < kCorePolls; ++i)
    if (((reg::read(address) & mask) != 0) == set) return true;
  return false;
}

/// Busy-waits about `cycles` CPU cycles (a few cycles per iteration; only a lower bound matters).
void delay_cycles(std::uint32_t cycles) {
  for (std::uint32_t i = 0; i < cycles / 4; ++i) asm volatile("" ::: "memory");
}

void configure_usb_pin(int pin) {
  const std::uintptr_t port = reg::gpio::port(0);  // GPIOA
  const int shift2 = 2 * pin;
  reg::modify(port + reg::gpio::kModer, 0b11u << shift2, reg::gpio::kModeAlternate << shift2);
  reg::modify(port + reg::gpio::kOspeedr, 0b11u << shift2, 0b11u << shift2);  // very high
  reg::modify(port + reg::gpio::kPupdr, 0b11u << shift2, 0);
  const int shift4 = 4 * (pin - 8);
  reg::modify(port + reg::gpio::kAfrh, 0xFu << shift4, 10u << shift4);  // AF10: OTG_FS
}

}  // namespace

void OtgFsDevice::defer_interrupt() {
  reg::clear_bits(otg::kGahbcfg, otg::kGahbcfgGintmsk);
}

void OtgFsDevice::init(std::uint32_t hclk_hz) {
  reg::set_bits(reg::rcc::kAhb1Enr, reg::rcc::kAhb1EnrGpioA);
  reg::set_bits(reg::rcc::kAhb2Enr, reg::rcc::kAhb2EnrOtgFs);
  (void)reg::read(reg::rcc::kAhb2Enr);  // the clock is on before the first access
  configure_usb_pin(11);                // DM
  configure_usb_pin(12);                // DP

  // Core soft reset once the AHB side is idle.
  wait_bits(otg::kGrstctl, otg::kGrstctlAhbidl, true);
  reg::set_bits(otg::kGrstctl, otg::kGrstctlCsrst);
  wait_bits(otg::kGrstctl, otg::kGrstctlCsrst, false);
  wait_bits(otg::kGrstctl, otg::kGrstctlAhbidl, true);

  reg::at(otg::kGusbcfg) = otg::kGusbcfgPhysel | otg::kGusbcfgFdmod |
                           otg_layout::turnaround_time(hclk_hz) << otg::kGusbcfgTrdtShift;
  delay_cycles(hclk_hz / 1000 * 25);  // forced device mode takes effect after 25 ms
  reg::at(otg::kGccfg) = otg::kGccfgPwrdwn | otg::kGccfgNovbussens;
  reg::at(otg::kPcgcctl) = 0;
  reg::set_bits(otg::kDctl, otg::kDctlSdis);  // stay disconnected until ready
  reg::at(otg::kDcfg) = otg::kDcfgDspdFullSpeed;

  reg::at(otg::kGrxfsiz) = kFifoPlan.rx_words;
  reg::at(otg::kDieptxf0) = otg_layout::tx_fifo_value(kFifoPlan.tx0_start(), kFifoPlan.tx0_words);
  reg::at(otg::dieptxf(1)) = otg_layout::tx_fifo_value(kFifoPlan.tx1_start(), kFifoPlan.tx1_words);
  flush_tx_fifo(otg::kGrstctlTxfnumAll);
  reg::set_bits(otg::kGrstctl, otg::kGrstctlRxfflsh);
  wait_bits(otg::kGrstctl, otg::kGrstctlRxfflsh, false);

  reg::at(otg::kDiepmsk) = otg::kEpintXfrc | otg::kEpintToc;
  reg::at(otg::kDoepmsk) = otg::kEpintXfrc | otg::kEpintStup;
  reg::at(otg::kDaintmsk) = 0;
  reg::at(otg::kGintsts) = 0xFFFFFFFF;  // write 1 to clear
  reg::at(otg::kGintmsk) =
      otg::kGintUsbrst | otg::kGintEnumdne | otg::kGintRxflvl | otg::kGintIepint | otg::kGintOepint;
  reg::at(otg::kGahbcfg) = otg::kGahbcfgGintmsk;
  // Lowest priority: its handler only masks the core's interrupt.
  *reinterpret_cast<volatile std::uint8_t*>(reg::nvic::kIpr0 +
                                            static_cast<std::uintptr_t>(reg::irq::kOtgFs)) =
      static_cast<std::uint8_t>(0xFu << (8 - reg::nvic::kPriorityBits));
  reg::at(reg::nvic::word_for(reg::nvic::kIser0, reg::irq::kOtgFs)) =
      reg::nvic::bit_for(reg::irq::kOtgFs);
  reg::clear_bits(otg::kDctl, otg::kDctlSdis);  // pull-up on: the host sees the device
}

void OtgFsDevice::disconnect() {
  reg::set_bits(otg::kDctl, otg::kDctlSdis);
}

bool OtgFsDevice::work_pending() const {
  return (reg::read(otg::kGintsts) & reg::read(otg::kGintmsk)) != 0;
}

void OtgFsDevice::poll() {
  // Bounded, so a babbling bus cannot starve the main loop (the rest waits for the next pass).
  for (int pass = 0; pass < 64; ++pass) {
    const std::uint32_t pending = reg::read(otg::kGintsts) & reg::read(otg::kGintmsk);
    if (pending == 0) break;
    if (pending & otg::kGintUsbrst) {
      reg::at(otg::kGintsts) = otg::kGintUsbrst;
      bus_reset();
    }
    if (pending & otg::kGintEnumdne) {
      reg::at(otg::kGintsts) = otg::kGintEnumdne;
      enumeration_done();
    }
    if (pending & otg::kGintRxflvl) read_rx_fifo();  // one entry per pass
    if (pending & otg::kGintOepint) out_endpoint_events();
    if (pending & otg::kGintIepint) in_endpoint_events();
  }
  reg::set_bits(otg::kGahbcfg, otg::kGahbcfgGintmsk);
}

// ---------------------------------------------------------------------------
// Core events

void OtgFsDevice::bus_reset() {
  flush_tx_fifo(otg::kGrstctlTxfnumAll);
  for (int ep = 0; ep < otg::kEndpoints; ++ep) {
    reg::at(otg::diepint(ep)) = 0xFF;
    reg::at(otg::doepint(ep)) = 0xFF;
    if (ep != 0) {
      reg::at(otg::diepctl(ep)) = otg::kEpctlSnak;
      reg::at(otg::doepctl(ep)) = otg::kEpctlSnak;
    }
  }
  reg::at(otg::kDaintmsk) = 1u << 0 | 1u << 16;  // EP0 IN and OUT
  reg::clear_bits(otg::kDcfg, otg::kDcfgDadMask);
  in_busy_ = 0;
  out_length_.fill(0);
  ep0_stage_ = Ep0Stage::kIdle;
  arm_ep0_setup();
  if (events_ != nullptr) events_->on_bus_reset();
}

void OtgFsDevice::enumeration_done() {
  // Full speed: EP0 max packet 64 (MPSIZ 0b00).
  reg::clear_bits(otg::diepctl(0), 0b11u);
  reg::at(otg::kDctl) = reg::read(otg::kDctl) | otg::kDctlCginak;
}

void OtgFsDevice::read_rx_fifo() {
  const otg_layout::RxStatus status = otg_layout::decode_rx_status(reg::read(otg::kGrxstsp));
  const int ep = status.endpoint;
  std::uint8_t* destination = nullptr;
  std::size_t room = 0;
  if (status.packet_status == otg::kPktstsSetupData) {
    destination = setup_.data();
    room = setup_.size();
  } else if (status.packet_status == otg::kPktstsOutData) {
    if (ep == 0 && ep0_stage_ == Ep0Stage::kOutData) {
      destination = ep0_out_.data() + ep0_out_received_;
      room = ep0_out_.size() - ep0_out_received_;
      ep0_out_received_ += std::min<std::size_t>(status.bytes, room);
    } else if (ep > 0 && ep < otg::kEndpoints) {
      destination = out_packet_[static_cast<std::size_t>(ep)].data();
      room = out_packet_[static_cast<std::size_t>(ep)].size();
      out_length_[static_cast<std::size_t>(ep)] = std::min<std::size_t>(status.bytes, room);
    }
  } else {
    return;  // SETUP done, OUT transfer done, global OUT NAK: no data
  }
  // Every word is popped, whether there is room for it or not.
  for (std::uint32_t i = 0; i < otg_layout::fifo_words(status.bytes); ++i) {
    const std::uint32_t word = reg::read(otg::fifo(0));
    for (std::uint32_t b = 0; b < 4; ++b) {
      const std::size_t at = 4 * i + b;
      if (at < status.bytes && at < room)
        destination[at] = static_cast<std::uint8_t>(word >> 8 * b);
    }
  }
}

void OtgFsDevice::out_endpoint_events() {
  const std::uint32_t endpoints = (reg::read(otg::kDaint) & reg::read(otg::kDaintmsk)) >> 16;
  for (int ep = 0; ep < otg::kEndpoints; ++ep) {
    if ((endpoints & (1u << ep)) == 0) continue;
    const std::uint32_t flags = reg::read(otg::doepint(ep));
    reg::at(otg::doepint(ep)) = flags;  // write 1 to clear
    if (ep != 0) {
      if ((flags & otg::kEpintXfrc) && events_ != nullptr)
        events_->on_out_packet(
            static_cast<std::uint8_t>(ep),
            std::span<const std::uint8_t>(out_packet_[static_cast<std::size_t>(ep)])
                .first(out_length_[static_cast<std::size_t>(ep)]));
      continue;
    }
    if (flags & otg::kEpintXfrc) {
      if (ep0_stage_ == Ep0Stage::kOutData) {
        const bool short_packet = ep0_out_received_ % 64 != 0;
        if (ep0_out_received_ >= ep0_out_.size() || short_packet) {
          ep0_stage_ = Ep0Stage::kIdle;
          if (events_ != nullptr) events_->on_ep0_out_complete(ep0_out_received_);
        } else {
          arm_ep0_out();
        }
      } else if (ep0_stage_ == Ep0Stage::kOutStatus) {
        ep0_stage_ = Ep0Stage::kIdle;
        if (events_ != nullptr) events_->on_ep0_status_complete();
      }
    }
    if (flags & otg::kEpintStup) {
      // A SETUP ends whatever control transfer was under way.
      ep0_stage_ = Ep0Stage::kIdle;
      flush_tx_fifo(0);
      arm_ep0_setup();
      if (events_ != nullptr) events_->on_setup(usb::SetupPacket::parse(setup_));
    }
  }
}

void OtgFsDevice::in_endpoint_events() {
  const std::uint32_t endpoints = reg::read(otg::kDaint) & reg::read(otg::kDaintmsk) & 0xFFFF;
  for (int ep = 0; ep < otg::kEndpoints; ++ep) {
    if ((endpoints & (1u << ep)) == 0) continue;
    const std::uint32_t flags = reg::read(otg::diepint(ep));
    reg::at(otg::diepint(ep)) = flags;
    if ((flags & otg::kEpintXfrc) == 0) continue;
    if (ep != 0) {
      in_busy_ &= ~(1u << ep);
      if (events_ != nullptr) events_->on_in_complete(static_cast<std::uint8_t>(0x80 | ep));
      continue;
    }
    if (ep0_stage_ == Ep0Stage::kInData) {
      if (ep0_in_sent_ < ep0_in_.size() || ep0_zero_length_end_) {
        send_ep0_packet();
      } else {
        ep0_stage_ = Ep0Stage::kOutStatus;
        arm_ep0_out();  // the host's zero-length status packet
      }
    } else if (ep0_stage_ == Ep0Stage::kInStatus) {
      ep0_stage_ = Ep0Stage::kIdle;
      if (events_ != nullptr) events_->on_ep0_status_complete();
    }
  }
}

// ---------------------------------------------------------------------------
// Endpoint 0

void OtgFsDevice::arm_ep0_setup() {
  // Up to three back-to-back SETUPs; OUT data stays NAKed (SETUPs are always taken).
  reg::at(otg::doeptsiz(0)) = otg_layout::ep0_out_transfer_size(64);
  reg::at(otg::doepctl(0)) = reg::read(otg::doepctl(0)) | otg::kEpctlEpena;
}

void OtgFsDevice::arm_ep0_out() {
  reg::at(otg::doeptsiz(0)) = otg_layout::ep0_out_transfer_size(64);
  reg::at(otg::doepctl(0)) = reg::read(otg::doepctl(0)) | otg::kEpctlCnak | otg::kEpctlEpena;
}

void OtgFsDevice::send_ep0_packet() {
  const std::size_t n = std::min<std::size_t>(64, ep0_in_.size() - ep0_in_sent_);
  if (n < 64) ep0_zero_length_end_ = false;  // a short packet ends the stage by itself
  reg::at(otg::dieptsiz(0)) = otg_layout::one_packet_transfer_size(static_cast<std::uint32_t>(n));
  reg::at(otg::diepctl(0)) = reg::read(otg::diepctl(0)) | otg::kEpctlCnak | otg::kEpctlEpena;
  write_fifo(0, ep0_in_.subspan(ep0_in_sent_, n));
  ep0_in_sent_ += n;
}

void OtgFsDevice::ep0_transmit(std::span<const std::uint8_t> data, bool zero_length_end) {
  ep0_stage_ = Ep0Stage::kInData;
  ep0_in_ = data;
  ep0_in_sent_ = 0;
  ep0_zero_length_end_ = zero_length_end;
  send_ep0_packet();
}

void OtgFsDevice::ep0_receive(std::span<std::uint8_t> buffer) {
  ep0_stage_ = Ep0Stage::kOutData;
  ep0_out_ = buffer;
  ep0_out_received_ = 0;
  arm_ep0_out();
}

void OtgFsDevice::ep0_status() {
  ep0_stage_ = Ep0Stage::kInStatus;
  reg::at(otg::dieptsiz(0)) = otg_layout::one_packet_transfer_size(0);
  reg::at(otg::diepctl(0)) = reg::read(otg::diepctl(0)) | otg::kEpctlCnak | otg::kEpctlEpena;
}

void OtgFsDevice::ep0_stall() {
  ep0_stage_ = Ep0Stage::kIdle;
  // Both directions; the core clears EP0's STALL at the next SETUP.
  reg::set_bits(otg::diepctl(0), otg::kEpctlStall);
  reg::set_bits(otg::doepctl(0), otg::kEpctlStall);
}

// ---------------------------------------------------------------------------
// Other endpoints

void OtgFsDevice::set_address(std::uint8_t address) {
  reg::modify(otg::kDcfg, otg::kDcfgDadMask,
              static_cast<std::uint32_t>(address) << otg::kDcfgDadShift);
}

void OtgFsDevice::open_endpoint(const usb::EndpointConfig& endpoint) {
  const int ep = usb::endpoint_number(endpoint.address);
  if (ep == 0 || ep >= otg::kEndpoints) return;
  if (usb::is_in_endpoint(endpoint.address)) {
    flush_tx_fifo(static_cast<std::uint32_t>(ep));
    reg::at(otg::diepctl(ep)) =
        otg_layout::endpoint_control(endpoint.type, endpoint.max_packet, ep);
    reg::set_bits(otg::kDaintmsk, 1u << ep);
    in_busy_ &= ~(1u << ep);
  } else {
    reg::at(otg::doepctl(ep)) = otg_layout::endpoint_control(endpoint.type, endpoint.max_packet, 0);
    reg::set_bits(otg::kDaintmsk, 1u << (16 + ep));
    out_max_packet_[static_cast<std::size_t>(ep)] = endpoint.max_packet;
  }
}

void OtgFsDevice::close_endpoint(std::uint8_t address) {
  const int ep = usb::endpoint_number(address);
  if (ep == 0 || ep >= otg::kEndpoints) return;
  if (usb::is_in_endpoint(address)) {
    if (reg::read(otg::diepctl(ep)) & otg::kEpctlEpena) {
      reg::set_bits(otg::diepctl(ep), otg::kEpctlSnak | otg::kEpctlEpdis);
      wait_bits(otg::diepint(ep), otg::kEpintEpdisd, true);
    }
    reg::at(otg::diepctl(ep)) = otg::kEpctlSnak;
    reg::at(otg::diepint(ep)) = 0xFF;
    flush_tx_fifo(static_cast<std::uint32_t>(ep));
    reg::clear_bits(otg::kDaintmsk, 1u << ep);
    in_busy_ &= ~(1u << ep);
  } else {
    reg::at(otg::doepctl(ep)) = otg::kEpctlSnak;
    reg::at(otg::doepint(ep)) = 0xFF;
    reg::clear_bits(otg::kDaintmsk, 1u << (16 + ep));
  }
}

void OtgFsDevice::set_stall(std::uint8_t address, bool stalled) {
  const int ep = usb::endpoint_number(address);
  if (ep == 0 || ep >= otg::kEndpoints) return;
  if (usb::is_in_endpoint(address)) {
    std::uint32_t ctl = reg::read(otg::diepctl(ep));
    if (stalled) {
      ctl |= otg::kEpctlStall | ((ctl & otg::kEpctlEpena) ? otg::kEpctlEpdis : 0);
    } else {
      ctl = (ctl & ~(otg::kEpctlStall | otg::kEpctlEpena)) | otg::kEpctlSd0pid | otg::kEpctlSnak;
    }
    reg::at(otg::diepctl(ep)) = ctl;
    flush_tx_fifo(static_cast<std::uint32_t>(ep));  // the queued packet is dropped
    in_busy_ &= ~(1u << ep);
  } else {
    std::uint32_t ctl = reg::read(otg::doepctl(ep));
    if (stalled) {
      ctl |= otg::kEpctlStall;
    } else {
      ctl = (ctl & ~(otg::kEpctlStall | otg::kEpctlEpena)) | otg::kEpctlSd0pid | otg::kEpctlSnak;
    }
    reg::at(otg::doepctl(ep)) = ctl;
  }
}

bool OtgFsDevice::transmit(std::uint8_t address, std::span<const std::uint8_t> packet) {
  const int ep = usb::endpoint_number(address);
  if (ep == 0 || ep >= otg::kEndpoints || !usb::is_in_endpoint(address) ||
      (in_busy_ & (1u << ep)) != 0)
    return false;
  const std::uint32_t ctl = reg::read(otg::diepctl(ep));
  if ((ctl & otg::kEpctlUsbaep) == 0 || (ctl & otg::kEpctlStall) != 0 ||
      packet.size() > (ctl & otg::kEpctlMpsizMask))
    return false;
  const auto words = otg_layout::fifo_words(static_cast<std::uint32_t>(packet.size()));
  if ((reg::read(otg::dtxfsts(ep)) & 0xFFFF) < words) return false;
  reg::at(otg::dieptsiz(ep)) =
      otg_layout::one_packet_transfer_size(static_cast<std::uint32_t>(packet.size()));
  reg::at(otg::diepctl(ep)) = ctl | otg::kEpctlCnak | otg::kEpctlEpena;
  write_fifo(ep, packet);
  in_busy_ |= 1u << ep;
  return true;
}

void OtgFsDevice::receive(std::uint8_t address) {
  const int ep = usb::endpoint_number(address);
  if (ep == 0 || ep >= otg::kEndpoints || usb::is_in_endpoint(address)) return;
  reg::at(otg::doeptsiz(ep)) =
      otg_layout::one_packet_transfer_size(out_max_packet_[static_cast<std::size_t>(ep)]);
  reg::at(otg::doepctl(ep)) = reg::read(otg::doepctl(ep)) | otg::kEpctlCnak | otg::kEpctlEpena;
}

// ---------------------------------------------------------------------------
// FIFOs

void OtgFsDevice::write_fifo(int ep, std::span<const std::uint8_t> data) {
  for (std::size_t at = 0; at < data.size(); at += 4) {
    std::uint32_t word = 0;
    std::memcpy(&word, data.data() + at, std::min<std::size_t>(4, data.size() - at));
    reg::at(otg::fifo(ep)) = word;
  }
}

void OtgFsDevice::flush_tx_fifo(std::uint32_t fifo) {
  reg::at(otg::kGrstctl) = otg::kGrstctlTxfflsh | fifo << otg::kGrstctlTxfnumShift;
  wait_bits(otg::kGrstctl, otg::kGrstctlTxfflsh, false);
}

}  // namespace flutterscan::firmware::stm32f4
