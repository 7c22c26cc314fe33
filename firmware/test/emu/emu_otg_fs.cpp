#include "emu_otg_fs.hpp"

#include <algorithm>
#include <cstdio>
#include <cstring>

namespace flutterscan::firmware::emu {
namespace {

// RM0090 34.16.2 core global registers.
constexpr std::uint32_t kGahbcfg = 0x008;
constexpr std::uint32_t kGusbcfg = 0x00C;
constexpr std::uint32_t kGrstctl = 0x010;
constexpr std::uint32_t kGintsts = 0x014;
constexpr std::uint32_t kGintmsk = 0x018;
constexpr std::uint32_t kGrxstsp = 0x020;
constexpr std::uint32_t kGrxfsiz = 0x024;
constexpr std::uint32_t kDieptxf0 = 0x028;
constexpr std::uint32_t kGccfg = 0x038;
constexpr std::uint32_t kDieptxf1 = 0x104;  // ..0x10C: endpoints 1..3
// 34.16.4 device registers.
constexpr std::uint32_t kDcfg = 0x800;
constexpr std::uint32_t kDctl = 0x804;
constexpr std::uint32_t kDsts = 0x808;
constexpr std::uint32_t kDiepmsk = 0x810;
constexpr std::uint32_t kDoepmsk = 0x814;
constexpr std::uint32_t kDaint = 0x818;
constexpr std::uint32_t kDaintmsk = 0x81C;
constexpr std::uint32_t kInEndpoints = 0x900;   // + 0x20 * ep: CTL 0, INT 8, TSIZ 0x10, TXFSTS 0x18
constexpr std::uint32_t kOutEndpoints = 0xB00;  // + 0x20 * ep: CTL 0, INT 8, TSIZ 0x10
constexpr std::uint32_t kPcgcctl = 0xE00;
constexpr std::uint32_t kFifoWindows = 0x1000;  // + 0x1000 * ep

constexpr std::uint32_t kGahbcfgGint = 1u << 0;
constexpr std::uint32_t kGusbcfgFdmod = 1u << 30;
constexpr std::uint32_t kGusbcfgFhmod = 1u << 29;
constexpr std::uint32_t kGrstctlCsrst = 1u << 0;
constexpr std::uint32_t kGrstctlRxfflsh = 1u << 4;
constexpr std::uint32_t kGrstctlTxfflsh = 1u << 5;
constexpr std::uint32_t kGrstctlAhbidl = 1u << 31;
constexpr std::uint32_t kGintRxflvl = 1u << 4;
constexpr std::uint32_t kGintUsbrst = 1u << 12;
constexpr std::uint32_t kGintEnumdne = 1u << 13;
constexpr std::uint32_t kGintIepint = 1u << 18;
constexpr std::uint32_t kGintOepint = 1u << 19;
constexpr std::uint32_t kGintLatched = kGintUsbrst | kGintEnumdne;
constexpr std::uint32_t kGccfgPwrdwn = 1u << 16;
constexpr std::uint32_t kDctlSdis = 1u << 1;
// DCTL: SGINAK 7, CGINAK 8, SGONAK 9, CGONAK 10, POPRGDNE 11 are write-only
// strobes; GINSTS 2 / GONSTS 3 read-only (no global NAK is modelled: setting
// one fails).
constexpr std::uint32_t kDctlStored = 0x3u | (0x7u << 4);
constexpr std::uint32_t kDctlGlobalNakSet = (1u << 7) | (1u << 9);
// DIEPCTLx / DOEPCTLx.
constexpr std::uint32_t kEpctlUsbaep = 1u << 15;
constexpr std::uint32_t kEpctlNaksts = 1u << 17;
constexpr std::uint32_t kEpctlStall = 1u << 21;
constexpr std::uint32_t kEpctlCnak = 1u << 26;
constexpr std::uint32_t kEpctlSnak = 1u << 27;
constexpr std::uint32_t kEpctlEpdis = 1u << 30;
constexpr std::uint32_t kEpctlEpena = 1u << 31;
/// Stored read/write bits of endpoint x > 0: MPSIZ 10:0, USBAEP, EPTYP 19:18,
/// SNPM 20 (OUT), TXFNUM 25:22 (IN).
constexpr std::uint32_t kEpctlStoredIn = 0x7FFu | kEpctlUsbaep | (0x3u << 18) | (0xFu << 22);
constexpr std::uint32_t kEpctlStoredOut = 0x7FFu | kEpctlUsbaep | (0x3u << 18) | (1u << 20);
// DIEPINTx / DOEPINTx.
constexpr std::uint32_t kEpintXfrc = 1u << 0;
constexpr std::uint32_t kEpintEpdisd = 1u << 1;
constexpr std::uint32_t kEpintStup = 1u << 3;
constexpr std::uint32_t kDiepintTxfe = 1u << 7;  // read-only: TX FIFO empty
// GRXSTSP packet status (device mode).
constexpr std::uint32_t kPktOutData = 2;
constexpr std::uint32_t kPktOutDone = 3;
constexpr std::uint32_t kPktSetupDone = 4;
constexpr std::uint32_t kPktSetupData = 6;

std::uint32_t rx_status(int ep, std::uint32_t bytes, std::uint32_t packet_status) {
  return static_cast<std::uint32_t>(ep) | (bytes & 0x7FFu) << 4 | packet_status << 17;
}

std::string hex(const char* what, std::uint32_t offset) {
  char b[96];
  std::snprintf(b, sizeof b, "%s OTG_FS+0x%03x", what, offset);
  return b;
}

}  // namespace

OtgFs::OtgFs() {
  core_reset();
}

void OtgFs::core_reset() {
  gintsts_latched_ = 0;
  rx_.clear();
  rx_current_.clear();
  rx_read_ = 0;
  for (auto& t : tx_) t.clear();
  for (int ep = 0; ep < kEndpoints; ++ep) {
    in_[ep] = Endpoint{};
    out_[ep] = Endpoint{};
  }
  in_[0].ctl = kEpctlUsbaep;
  out_[0].ctl = kEpctlUsbaep;
}

bool OtgFs::attached() const {
  return (dctl_ & kDctlSdis) == 0 && (gccfg_ & kGccfgPwrdwn) != 0 &&
         (gusbcfg_ & kGusbcfgFdmod) != 0;
}

bool OtgFs::interrupt_line() const {
  return (gahbcfg_ & kGahbcfgGint) != 0 && (gintsts() & gintmsk_) != 0;
}

std::uint32_t OtgFs::daint() const {
  std::uint32_t v = 0;
  for (int ep = 0; ep < kEndpoints; ++ep) {
    if ((in_[ep].intr & diepmsk_) != 0) v |= 1u << ep;
    if ((out_[ep].intr & doepmsk_) != 0) v |= 1u << (16 + ep);
  }
  return v;
}

std::uint32_t OtgFs::gintsts() const {
  std::uint32_t v = gintsts_latched_;  // CMOD 0: device mode
  if (!rx_.empty()) v |= kGintRxflvl;
  const std::uint32_t pending = daint() & daintmsk_;
  if ((pending & 0xFFFFu) != 0) v |= kGintIepint;
  if ((pending >> 16) != 0) v |= kGintOepint;
  return v;
}

std::uint32_t OtgFs::in_ctl(int ep) const {
  return in_[ep].ctl | (in_[ep].nak ? kEpctlNaksts : 0u);
}

std::uint32_t OtgFs::out_ctl(int ep) const {
  return out_[ep].ctl | (out_[ep].nak ? kEpctlNaksts : 0u);
}

int OtgFs::tx_fifo_of(int ep) const {
  return ep == 0 ? 0 : static_cast<int>((in_[ep].ctl >> 22) & 0xFu);
}

std::uint32_t OtgFs::tx_depth(int fifo) const {
  return dieptxf_[fifo] >> 16;
}

std::uint32_t OtgFs::rx_used_words() const {
  std::uint32_t n = static_cast<std::uint32_t>(rx_current_.size() - rx_read_);
  for (const RxEntry& e : rx_) n += 1 + static_cast<std::uint32_t>(e.words.size());
  return n;
}

void OtgFs::write_ctl(Endpoint& e, int ep, std::uint32_t stored, std::uint32_t value) {
  e.ctl = (e.ctl & ~stored) | (value & stored);
  // STALL: endpoint 0 only sets it (the core clears it at a SETUP); others read/write.
  if (ep == 0)
    e.ctl |= value & kEpctlStall;
  else
    e.ctl = (e.ctl & ~kEpctlStall) | (value & kEpctlStall);
  if ((value & kEpctlSnak) != 0) e.nak = true;
  if ((value & kEpctlCnak) != 0) e.nak = false;
  if ((value & kEpctlEpdis) != 0 && (e.ctl & kEpctlEpena) != 0) {
    e.ctl &= ~kEpctlEpena;
    e.intr |= kEpintEpdisd;
  } else if ((value & kEpctlEpena) != 0) {
    e.ctl |= kEpctlEpena;
  }
}

std::uint32_t OtgFs::pop_status(std::string* error) {
  if (rx_read_ < rx_current_.size()) {
    *error = "GRXSTSP popped with words of the last packet left in the RX FIFO";
    return 0;
  }
  if (rx_.empty()) {
    *error = "GRXSTSP read with the RX FIFO empty (GINTSTS.RXFLVL 0)";
    return 0;
  }
  RxEntry entry = std::move(rx_.front());
  rx_.pop_front();
  rx_current_ = std::move(entry.words);
  rx_read_ = 0;
  const int ep = static_cast<int>(entry.status & 0xFu);
  const std::uint32_t packet_status = (entry.status >> 17) & 0xFu;
  // 34.17.5: these two patterns raise their endpoint interrupt as they are popped.
  if (packet_status == kPktOutDone) {
    out_[ep].intr |= kEpintXfrc;
  } else if (packet_status == kPktSetupDone) {
    out_[ep].intr |= kEpintStup;
    out_[ep].ctl &= ~kEpctlEpena;
  }
  return entry.status;
}

bool OtgFs::read(std::uint32_t offset, std::uint32_t* value, std::string* error) {
  if (offset >= kFifoWindows) {  // any window pops the RX FIFO
    if (rx_read_ >= rx_current_.size()) {
      *error = hex("read of the RX FIFO beyond the popped packet at", offset);
      return false;
    }
    *value = rx_current_[rx_read_++];
    return true;
  }
  if (offset >= kInEndpoints && offset < kInEndpoints + 0x20 * kEndpoints) {
    const int ep = static_cast<int>((offset - kInEndpoints) / 0x20);
    switch ((offset - kInEndpoints) % 0x20) {
      case 0x00:
        *value = in_ctl(ep);
        return true;
      case 0x08:
        *value = in_[ep].intr | (tx_[tx_fifo_of(ep)].empty() ? kDiepintTxfe : 0u);
        return true;
      case 0x10:
        *value = in_[ep].tsiz;
        return true;
      case 0x18: {
        const int f = tx_fifo_of(ep);
        *value = tx_depth(f) - static_cast<std::uint32_t>(tx_[f].size());
        return true;
      }
      default:
        break;
    }
  } else if (offset >= kOutEndpoints && offset < kOutEndpoints + 0x20 * kEndpoints) {
    const int ep = static_cast<int>((offset - kOutEndpoints) / 0x20);
    switch ((offset - kOutEndpoints) % 0x20) {
      case 0x00:
        *value = out_ctl(ep);
        return true;
      case 0x08:
        *value = out_[ep].intr;
        return true;
      case 0x10:
        *value = out_[ep].tsiz;
        return true;
      default:
        break;
    }
  } else if (offset >= kDieptxf1 && offset < kDieptxf1 + 4 * (kEndpoints - 1)) {
    *value = dieptxf_[1 + (offset - kDieptxf1) / 4];
    return true;
  } else {
    switch (offset) {
      case kGahbcfg:
        *value = gahbcfg_;
        return true;
      case kGusbcfg:
        *value = gusbcfg_;
        return true;
      case kGrstctl:
        *value = kGrstctlAhbidl;
        return true;  // resets and flushes end at once
      case kGintsts:
        *value = gintsts();
        return true;
      case kGintmsk:
        *value = gintmsk_;
        return true;
      case kGrxstsp:
        *value = pop_status(error);
        return error->empty();
      case kGrxfsiz:
        *value = grxfsiz_;
        return true;
      case kDieptxf0:
        *value = dieptxf_[0];
        return true;
      case kGccfg:
        *value = gccfg_;
        return true;
      case kDcfg:
        *value = dcfg_;
        return true;
      case kDctl:
        *value = dctl_;
        return true;
      case kDsts:
        *value = dsts_;
        return true;
      case kDiepmsk:
        *value = diepmsk_;
        return true;
      case kDoepmsk:
        *value = doepmsk_;
        return true;
      case kDaint:
        *value = daint();
        return true;
      case kDaintmsk:
        *value = daintmsk_;
        return true;
      case kPcgcctl:
        *value = pcgcctl_;
        return true;
      default:
        break;
    }
  }
  *error = hex("read of", offset) + " (not modelled)";
  return false;
}

bool OtgFs::write(std::uint32_t offset, std::uint32_t value, std::string* error) {
  const bool device_register = offset >= 0x800 && offset < 0xE00;
  if (device_register && (gusbcfg_ & kGusbcfgFdmod) == 0) {
    *error = hex("device register written before GUSBCFG.FDMOD (forced device mode):", offset);
    return false;
  }
  if (offset >= kFifoWindows) {
    const int ep = static_cast<int>(offset / kFifoWindows) - 1;
    const int f = tx_fifo_of(ep);
    if (tx_[f].size() >= tx_depth(f)) {
      *error = hex("push into a full TX FIFO at", offset);
      return false;
    }
    tx_[f].push_back(value);
    return true;
  }
  if (offset >= kInEndpoints && offset < kInEndpoints + 0x20 * kEndpoints) {
    const int ep = static_cast<int>((offset - kInEndpoints) / 0x20);
    switch ((offset - kInEndpoints) % 0x20) {
      case 0x00:
        write_ctl(in_[ep], ep, ep == 0 ? 0x3u : kEpctlStoredIn, value);  // EP0: MPSIZ 1:0
        return true;
      case 0x08:
        in_[ep].intr &= ~value;
        return true;  // rc_w1
      case 0x10:
        in_[ep].tsiz = value;
        return true;
      default:
        break;
    }
  } else if (offset >= kOutEndpoints && offset < kOutEndpoints + 0x20 * kEndpoints) {
    const int ep = static_cast<int>((offset - kOutEndpoints) / 0x20);
    switch ((offset - kOutEndpoints) % 0x20) {
      case 0x00:
        write_ctl(out_[ep], ep, ep == 0 ? 0u : kEpctlStoredOut, value);
        return true;
      case 0x08:
        out_[ep].intr &= ~value;
        return true;
      case 0x10:
        out_[ep].tsiz = value;
        return true;
      default:
        break;
    }
  } else if (offset >= kDieptxf1 && offset < kDieptxf1 + 4 * (kEndpoints - 1)) {
    dieptxf_[1 + (offset - kDieptxf1) / 4] = value;
    return true;
  } else {
    switch (offset) {
      case kGahbcfg:
        if ((value & ~kGahbcfgGint) != 0) break;  // DMA, FIFO-empty levels: not modelled
        gahbcfg_ = value;
        return true;
      case kGusbcfg:
        if ((value & kGusbcfgFhmod) != 0) break;  // host mode
        gusbcfg_ = value;
        return true;
      case kGrstctl:
        if ((value & kGrstctlCsrst) != 0) core_reset();
        if ((value & kGrstctlRxfflsh) != 0) {
          rx_.clear();
          rx_current_.clear();
          rx_read_ = 0;
        }
        if ((value & kGrstctlTxfflsh) != 0) {
          const std::uint32_t n = (value >> 6) & 0x1Fu;
          if (n == 0x10) {
            for (auto& t : tx_) t.clear();
          } else if (n < static_cast<std::uint32_t>(kEndpoints)) {
            tx_[n].clear();
          } else {
            break;
          }
        }
        if ((value & ~(kGrstctlCsrst | kGrstctlRxfflsh | kGrstctlTxfflsh | (0x1Fu << 6) |
                       kGrstctlAhbidl)) != 0)  // AHBIDL: read-only
          break;
        return true;
      case kGintsts:
        gintsts_latched_ &= ~(value & kGintLatched);
        return true;
      case kGintmsk:
        gintmsk_ = value;
        return true;
      case kGrxfsiz:
        grxfsiz_ = value;
        return true;
      case kDieptxf0:
        dieptxf_[0] = value;
        return true;
      case kGccfg:
        gccfg_ = value;
        return true;
      case kDcfg:
        dcfg_ = value;
        return true;
      case kDctl:
        if ((value & kDctlGlobalNakSet) != 0) break;
        dctl_ = value & kDctlStored;
        return true;
      case kDiepmsk:
        diepmsk_ = value;
        return true;
      case kDoepmsk:
        doepmsk_ = value;
        return true;
      case kDaintmsk:
        daintmsk_ = value;
        return true;
      case kPcgcctl:
        pcgcctl_ = value;
        return true;
      default:
        break;
    }
  }
  char b[32];
  std::snprintf(b, sizeof b, " value 0x%08x", value);
  *error = hex("write of", offset) + b + " (not modelled)";
  return false;
}

void OtgFs::bus_reset() {
  gintsts_latched_ |= kGintUsbrst;
  dcfg_ &= ~(0x7Fu << 4);  // the device answers address 0 after a reset
}

void OtgFs::enumeration_done() {
  gintsts_latched_ |= kGintEnumdne;
  dsts_ = (dsts_ & ~0x6u) | (0x3u << 1);  // ENUMSPD: full speed (48 MHz PHY clock)
}

bool OtgFs::push_rx(int ep, std::uint32_t packet_status, std::span<const std::uint8_t> data,
                    std::uint32_t then_status) {
  const std::uint32_t words = static_cast<std::uint32_t>((data.size() + 3) / 4);
  if (rx_used_words() + words + 2 > (grxfsiz_ & 0xFFFFu)) return false;
  RxEntry entry{rx_status(ep, static_cast<std::uint32_t>(data.size()), packet_status), {}};
  for (std::uint32_t i = 0; i < words; ++i) {
    std::uint32_t w = 0;
    std::memcpy(&w, data.data() + 4 * i, std::min<std::size_t>(4, data.size() - 4 * i));
    entry.words.push_back(w);
  }
  rx_.push_back(std::move(entry));
  rx_.push_back({rx_status(ep, 0, then_status), {}});
  return true;
}

OtgFs::Handshake OtgFs::setup(const std::array<std::uint8_t, 8>& packet) {
  if (!attached()) return Handshake::kNoDevice;
  if (!push_rx(0, kPktSetupData, packet, kPktSetupDone)) return Handshake::kNak;
  in_[0].ctl &= ~kEpctlStall;
  out_[0].ctl &= ~kEpctlStall;
  in_[0].nak = true;
  out_[0].nak = true;
  return Handshake::kAck;
}

OtgFs::Handshake OtgFs::out(int ep, std::span<const std::uint8_t> packet) {
  if (!attached()) return Handshake::kNoDevice;
  Endpoint& e = out_[ep];
  if ((e.ctl & kEpctlStall) != 0) return Handshake::kStall;
  if ((e.ctl & kEpctlEpena) == 0 || e.nak) return Handshake::kNak;
  const std::uint32_t max_packet = ep == 0 ? 64u : (e.ctl & 0x7FFu);
  if (packet.size() > max_packet) return Handshake::kStall;  // babble: not modelled further
  if (!push_rx(ep, kPktOutData, packet, kPktOutDone)) return Handshake::kNak;
  // One packet ends the transfer (PKTCNT 1): the endpoint disables itself.
  const std::uint32_t size_mask = ep == 0 ? 0x7Fu : 0x7FFFFu;
  const std::uint32_t left =
      (e.tsiz & size_mask) -
      std::min<std::uint32_t>(e.tsiz & size_mask, static_cast<std::uint32_t>(packet.size()));
  e.tsiz = (e.tsiz & ~(size_mask | (0x3FFu << 19))) | left;
  e.ctl &= ~kEpctlEpena;
  e.nak = true;
  return Handshake::kAck;
}

OtgFs::Handshake OtgFs::in(int ep, std::vector<std::uint8_t>* packet) {
  if (!attached()) return Handshake::kNoDevice;
  Endpoint& e = in_[ep];
  if ((e.ctl & kEpctlStall) != 0) return Handshake::kStall;
  if ((e.ctl & kEpctlEpena) == 0 || e.nak) return Handshake::kNak;
  const std::uint32_t size_mask = ep == 0 ? 0x7Fu : 0x7FFFFu;
  const std::uint32_t bytes = e.tsiz & size_mask;
  const std::uint32_t words = (bytes + 3) / 4;
  auto& fifo = tx_[tx_fifo_of(ep)];
  if (fifo.size() < words) return Handshake::kNak;  // the packet is not all in the FIFO yet
  packet->clear();
  for (std::uint32_t i = 0; i < words; ++i) {
    const std::uint32_t w = fifo.front();
    fifo.pop_front();
    for (std::uint32_t b = 0; b < 4 && 4 * i + b < bytes; ++b)
      packet->push_back(static_cast<std::uint8_t>(w >> (8 * b)));
  }
  e.tsiz &= ~(size_mask | (0x3FFu << 19));
  e.ctl &= ~kEpctlEpena;
  e.intr |= kEpintXfrc;
  return Handshake::kAck;
}

}  // namespace flutterscan::firmware::emu
