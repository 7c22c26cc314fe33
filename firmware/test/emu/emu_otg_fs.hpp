#pragma once
// The OTG_FS core of the emulated STM32F405 in device mode (emu_chip.hpp),
// written from RM0090 chapter 34: the registers the product image's driver
// touches (34.16: global GAHBCFG, GUSBCFG, GRSTCTL, GINTSTS, GINTMSK, GRXSTSP,
// GRXFSIZ, DIEPTXF0/1..3, GCCFG; device DCFG, DCTL, DSTS, DIEPMSK, DOEPMSK,
// DAINT, DAINTMSK, DIEPCTL/DIEPINT/DIEPTSIZ/DTXFSTS and DOEPCTL/DOEPINT/
// DOEPTSIZ of endpoints 0..3; PCGCCTL), the shared RX FIFO (status entries and
// packet words, popped through GRXSTSP and the FIFO window) and one TX FIFO
// per IN endpoint, each as deep as the application made it.
//
// The bus side is the host's (emu_usb_host.hpp): a reset and the end of
// enumeration at full speed, then SETUP, OUT and IN transactions, each
// answered ACK, NAK or STALL as the core would from its registers: an OUT
// needs its endpoint enabled, not NAKing and room in the RX FIFO; an IN
// needs the endpoint enabled, not NAKing and the whole packet in its TX FIFO.
// SETUP is always taken (it sets NAK on endpoint 0 both ways and clears its
// STALL). XFRC/STUP are raised as the application pops the "transfer
// completed" / "SETUP done" entry (34.17.5). Not modelled (fail loudly):
// any other register, host mode, DMA, SOF/suspend/resume, isochronous and
// multi-packet transfers; data toggles are not checked.

#include <array>
#include <cstdint>
#include <deque>
#include <span>
#include <string>
#include <vector>

namespace flutterscan::firmware::emu {

class OtgFs {
 public:
  static constexpr std::uint32_t kBase = 0x50000000;
  /// Registers (0x000..0xFFF) and the FIFO windows of endpoints 0..3.
  static constexpr std::uint32_t kSize = 0x5000;
  static constexpr int kEndpoints = 4;

  OtgFs();

  // Core side: a word access at `offset`; false (and `error`) if not modelled.
  bool read(std::uint32_t offset, std::uint32_t* value, std::string* error);
  bool write(std::uint32_t offset, std::uint32_t value, std::string* error);
  /// The core's interrupt line to the NVIC (GINTSTS & GINTMSK, gated by GAHBCFG.GINTMSK).
  bool interrupt_line() const;

  // Bus side.
  enum class Handshake { kAck, kNak, kStall, kNoDevice };
  /// The device's pull-up is on (DCTL.SDIS 0, transceiver powered): the host sees it.
  bool attached() const;
  /// A bus reset (GINTSTS.USBRST), then its end at full speed (ENUMDNE, DSTS.ENUMSPD).
  void bus_reset();
  void enumeration_done();
  /// The address the device answers to (DCFG.DAD).
  std::uint8_t address() const { return static_cast<std::uint8_t>((dcfg_ >> 4) & 0x7Fu); }
  Handshake setup(const std::array<std::uint8_t, 8>& packet);
  Handshake out(int ep, std::span<const std::uint8_t> packet);
  Handshake in(int ep, std::vector<std::uint8_t>* packet);

 private:
  /// An IN or OUT endpoint's registers.
  struct Endpoint {
    std::uint32_t ctl = 0;  // stored bits (EPENA, STALL, TXFNUM (IN), EPTYP, USBAEP, MPSIZ)
    bool nak = false;
    std::uint32_t intr = 0;
    std::uint32_t tsiz = 0;
  };
  struct RxEntry {
    std::uint32_t status;
    std::vector<std::uint32_t> words;
  };

  std::uint32_t gintsts() const;
  std::uint32_t daint() const;
  std::uint32_t in_ctl(int ep) const;
  std::uint32_t out_ctl(int ep) const;
  /// A write to endpoint `ep`'s DIEPCTL / DOEPCTL; `stored`: the bits it keeps.
  static void write_ctl(Endpoint& e, int ep, std::uint32_t stored, std::uint32_t value);
  std::uint32_t pop_status(std::string* error);
  int tx_fifo_of(int ep) const;
  std::uint32_t tx_depth(int fifo) const;
  std::uint32_t rx_used_words() const;
  bool push_rx(int ep, std::uint32_t packet_status, std::span<const std::uint8_t> data,
               std::uint32_t then_status);
  void core_reset();

  std::uint32_t gahbcfg_ = 0;
  std::uint32_t gusbcfg_ = 0x00000A00;
  std::uint32_t gintsts_latched_ = 0;  // rc_w1 bits: USBRST, ENUMDNE
  std::uint32_t gintmsk_ = 0;
  std::uint32_t grxfsiz_ = 0x200;
  std::uint32_t dieptxf_[kEndpoints] = {0x02000200, 0x02000400, 0x02000400, 0x02000400};
  std::uint32_t gccfg_ = 0;
  std::uint32_t dcfg_ = 0x02200000;
  std::uint32_t dctl_ = 0;
  std::uint32_t dsts_ = 0x00000010;
  std::uint32_t diepmsk_ = 0;
  std::uint32_t doepmsk_ = 0;
  std::uint32_t daintmsk_ = 0;
  std::uint32_t pcgcctl_ = 0;
  std::array<Endpoint, kEndpoints> in_{};
  std::array<Endpoint, kEndpoints> out_{};
  std::deque<RxEntry> rx_;
  std::vector<std::uint32_t> rx_current_;  // words of the popped entry still to be read
  std::size_t rx_read_ = 0;
  std::array<std::deque<std::uint32_t>, kEndpoints> tx_;
};

}  // namespace flutterscan::firmware::emu
