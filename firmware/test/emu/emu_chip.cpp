#include "emu_chip.hpp"

#include <algorithm>
#include <cstdio>

namespace flutterscan::firmware::emu {
namespace {

// TIM1 (RM0090 17.4) / TIM2 (18.4) bits the model acts on.
constexpr std::uint32_t kCr1Cen = 1u << 0;
constexpr std::uint32_t kCr1Urs = 1u << 2;
constexpr std::uint32_t kDierUie = 1u << 0;
constexpr std::uint32_t kDierCc1Ie = 1u << 1;
constexpr std::uint32_t kDierCc2Ie = 1u << 2;
constexpr std::uint32_t kDierUde = 1u << 8;
constexpr std::uint32_t kSrUif = 1u << 0;
constexpr std::uint32_t kSrCc1If = 1u << 1;
constexpr std::uint32_t kSrCc2If = 1u << 2;
constexpr std::uint32_t kSrTif = 1u << 6;
constexpr std::uint32_t kSrCc1Of = 1u << 9;
constexpr std::uint32_t kSrCc2Of = 1u << 10;
constexpr std::uint32_t kEgrUg = 1u << 0;
constexpr std::uint32_t kTimDier = 0x0C;
constexpr std::uint32_t kTimEgr = 0x14;
constexpr std::uint32_t kTimCcmr1 = 0x18;
constexpr std::uint32_t kTimCcer = 0x20;
constexpr std::uint32_t kTimCnt = 0x24;
constexpr std::uint32_t kTimPsc = 0x28;
constexpr std::uint32_t kTimArr = 0x2C;
constexpr std::uint32_t kTimCcr1 = 0x34;
constexpr std::uint32_t kTimCcr2 = 0x38;
constexpr std::uint32_t kTimCr2 = 0x04;
// DMA2 (RM0090 10.5): HISR 0x04, HIFCR 0x0C, stream 5 at 0x10 + 0x18 * 5;
// stream 5's flags at bit 6 of HISR: FEIF 6, DMEIF 8, TEIF 9, HTIF 10, TCIF 11.
constexpr std::uint32_t kDmaLisr = 0x00;
constexpr std::uint32_t kDmaHisr = 0x04;
constexpr std::uint32_t kDmaLifcr = 0x08;
constexpr std::uint32_t kDmaHifcr = 0x0C;
constexpr std::uint32_t kS5 = 0x10 + 0x18 * 5;
constexpr std::uint32_t kS5Cr = kS5 + 0x00;
constexpr std::uint32_t kS5Ndtr = kS5 + 0x04;
constexpr std::uint32_t kS5Par = kS5 + 0x08;
constexpr std::uint32_t kS5M0ar = kS5 + 0x0C;
constexpr std::uint32_t kS5Fcr = kS5 + 0x14;
constexpr std::uint32_t kS5FlagHt = 1u << 10;
constexpr std::uint32_t kS5FlagTc = 1u << 11;
constexpr std::uint32_t kDmaCrEn = 1u << 0;
constexpr std::uint32_t kDmaCrTcie = 1u << 4;
// What the model moves: channel 6 (TIM1_UP), memory to peripheral, memory
// increment, 32-bit both sides; no circular, double-buffer or peripheral increment.
constexpr std::uint32_t kDmaCrModelledMask = (0x7u << 25) | (1u << 18) | (0x3u << 13) |
                                             (0x3u << 11) | (1u << 10) | (1u << 9) | (1u << 8) |
                                             (0x3u << 6);
constexpr std::uint32_t kDmaCrModelled =
    (6u << 25) | (0x2u << 13) | (0x2u << 11) | (1u << 10) | (0x1u << 6);
// Flash interface (RM0090 3.9): OPTCR OPTLOCK 0, OPTSTRT 1; SR BSY 16.
constexpr std::uint32_t kOptcrOptLock = 1u << 0;
constexpr std::uint32_t kOptcrOptStrt = 1u << 1;
constexpr std::uint32_t kFlashSrBsy = 1u << 16;
constexpr std::uint32_t kFlashKeyr = kFlashIfBase + 0x04;
constexpr std::uint32_t kFlashCr = kFlashIfBase + 0x10;
constexpr std::uint32_t kKey1 = 0x45670123;
constexpr std::uint32_t kKey2 = 0xCDEF89AB;
// FLASH_CR: PG 0, SER 1, MER 2, SNB 6:3, PSIZE 9:8 (0b10: x32), STRT 16, LOCK 31.
constexpr std::uint32_t kCrPg = 1u << 0;
constexpr std::uint32_t kCrSer = 1u << 1;
constexpr std::uint32_t kCrMer = 1u << 2;
constexpr std::uint32_t kCrPsizeMask = 0x3u << 8;
constexpr std::uint32_t kCrPsizeX32 = 0x2u << 8;
constexpr std::uint32_t kCrStrt = 1u << 16;
constexpr std::uint32_t kCrLock = 1u << 31;
constexpr std::uint32_t kCrModelled =
    kCrPg | kCrSer | (0xFu << 3) | kCrPsizeMask | kCrStrt | kCrLock;
// FLASH_SR: EOP 0, OPERR 1, WRPERR 4, PGAERR 5, PGPERR 6, PGSERR 7 (rc_w1), BSY 16.
constexpr std::uint32_t kSrFlags = 0xF3u;
constexpr std::uint32_t kSrWrperr = 1u << 4;
constexpr std::uint32_t kOptKey1 = 0x08192A3B;
constexpr std::uint32_t kOptKey2 = 0x4C5D6E7F;
// NVIC (PM0214 4.2): ISER, ICER, ISPR, ICPR words for interrupts 0..95.
constexpr std::uint32_t kIser = 0x100;
constexpr std::uint32_t kIcer = 0x180;
constexpr std::uint32_t kIspr = 0x200;
constexpr std::uint32_t kIcpr = 0x280;
/// A bounded run: a test never hangs.
constexpr std::uint64_t kMaxSlices = 400'000'000 / 64;

}  // namespace

Chip::Chip() {
  if (uc_open(UC_ARCH_ARM, static_cast<uc_mode>(UC_MODE_THUMB | UC_MODE_MCLASS), &uc_) !=
      UC_ERR_OK) {
    fail("uc_open");
    return;
  }
  // Flash is mapped writable so that a store reaches flash_store (programming
  // through the flash interface); any other store there fails.
  if (uc_ctl_set_cpu_model(uc_, UC_CPU_ARM_CORTEX_M4) != UC_ERR_OK ||
      uc_mem_map(uc_, kFlashBase, kFlashSize, UC_PROT_ALL) != UC_ERR_OK ||
      uc_mem_map(uc_, kSramBase, kSramSize, UC_PROT_ALL) != UC_ERR_OK)
    fail("mapping flash and SRAM");
  const std::vector<std::uint8_t> erased(kFlashSize, 0xFF);
  uc_mem_write(uc_, kFlashBase, erased.data(), erased.size());
  const std::uint16_t bkpt = 0xBE00;  // the exception return trampoline (never executed)
  uc_mem_write(uc_, kTrampoline, &bkpt, sizeof bkpt);
  // SRAM after power-on: not zero, not a valid record.
  std::vector<std::uint8_t> sram(kSramSize);
  for (std::size_t i = 0; i < sram.size(); ++i) sram[i] = static_cast<std::uint8_t>(i * 37 + 11);
  uc_mem_write(uc_, kSramBase, sram.data(), sram.size());
  model_registers();
  for (const std::uint32_t block :
       {kRccBase, kFlashIfBase, kPwrBase, kGpioABase, kGpioBBase, kGpioCBase, kTim1Base, kTim2Base,
        kTim3Base, kTim5Base, kDma2Base, kIwdgBase, kDbgmcuBase})
    map_region(block, 0x400);
  map_region(kScsBase, 0x1000);
  map_region(OtgFs::kBase, OtgFs::kSize);
  map_region(kUniqueIdPage, 0x1000);
  uc_hook hook;
  uc_hook_add(uc_, &hook, UC_HOOK_MEM_UNMAPPED, reinterpret_cast<void*>(&Chip::unmapped), this, 1,
              0);
  uc_hook_add(uc_, &hook, UC_HOOK_MEM_WRITE, reinterpret_cast<void*>(&Chip::flash_store), this,
              kFlashBase, kFlashBase + kFlashSize - 1);
  stop_at(kTrampoline, "return");
}

Chip::~Chip() {
  if (uc_ != nullptr) uc_close(uc_);
}

void Chip::write(std::uint32_t address, const std::vector<std::uint8_t>& bytes) {
  if (uc_mem_write(uc_, address, bytes.data(), bytes.size()) != UC_ERR_OK) fail("write");
}

void Chip::write_word(std::uint32_t address, std::uint32_t value) {
  if (uc_mem_write(uc_, address, &value, 4) != UC_ERR_OK) fail("write_word");
}

std::uint32_t Chip::read_word(std::uint32_t address) {
  std::uint32_t v = 0;
  uc_mem_read(uc_, address, &v, 4);
  return v;
}

void Chip::stop_at(std::uint32_t address, const char* name) {
  stops_.push_back({address & ~1u, name});
  uc_hook hook;
  uc_hook_add(uc_, &hook, UC_HOOK_CODE, reinterpret_cast<void*>(&Chip::on_code), this,
              address & ~1u, address & ~1u);
}

void Chip::sleep_at(std::uint32_t address) {
  stop_at(address, "wfi");
}

void Chip::set_option_bytes(std::uint32_t optcr) {
  regs_[kFlashOptcr] = optcr | kOptcrOptLock;
}

void Chip::set_reset_flags(std::uint32_t flags) {
  std::uint32_t& csr = regs_[kRccBase + 0x74];
  csr = (csr & 0x01FFFFFFu) | (flags & 0xFE000000u);
}

std::string Chip::run() {
  const std::uint32_t sp = read_word(kFlashBase);
  const std::uint32_t pc = read_word(kFlashBase + 4);
  uc_reg_write(uc_, UC_ARM_REG_SP, &sp);
  return go(pc, false);
}

void Chip::system_reset(bool by_watchdog) {
  // PM0214 4.3.5 SYSRESETREQ, or the independent watchdog (RM0090 21.3): a
  // system reset. Flash, SRAM and the option bytes keep their contents; every
  // peripheral (the IWDG too: software watchdog mode) and the core start over;
  // RCC_CSR keeps its flags and adds SFTRSTF or IWDGRSTF, and PINRSTF (the
  // reset circuit drives NRST on any internal reset, RM0090 6.1.2).
  reset_requested_ = false;
  iwdg_zero_ = kNever;
  iwdg_unlocked_ = false;
  iwdg_expired_ = false;
  const std::uint32_t optcr = regs_.at(kFlashOptcr);
  const std::uint32_t csr_flags = regs_.at(kRccBase + 0x74) & 0xFF000000u;
  std::vector<std::uint32_t> otp;  // non-volatile, like the option bytes
  for (std::uint32_t a = kOtpBase; a < kOtpBase + kOtpSize; a += 4) otp.push_back(regs_.at(a));
  regs_.clear();
  model_registers();
  for (std::uint32_t i = 0; i < otp.size(); ++i) regs_[kOtpBase + 4 * i] = otp[i];
  regs_[kFlashOptcr] = optcr | kOptcrOptLock;
  regs_[kRccBase + 0x74] = (regs_.at(kRccBase + 0x74) & 0x00FFFFFFu) | csr_flags |
                           (by_watchdog ? 1u << 29 : 1u << 28) | 1u << 26;
  otg_ = OtgFs();
  tim2_start_ = 0;
  tim2_count0_ = 0;
  tim1_next_update_ = kNever;
  dma_index_ = dma_total_ = 0;
  systick_zero_ = kNever;
  systick_pending_ = false;
  sleeping_ = false;
  for (int i = 0; i < 3; ++i) nvic_enabled_[i] = nvic_pending_[i] = 0;
  optkey_step_ = 0;
  flash_key_step_ = 0;
  flash_busy_reads_ = 0;
  if (by_watchdog)
    watchdog_resets_.push_back(cycles_);
  else
    ++system_resets_;
  const std::uint32_t sp = read_word(kFlashBase);
  const std::uint32_t pc = read_word(kFlashBase + 4) & ~1u;
  const std::uint32_t xpsr = 0x01000000u, zero = 0, lr = 0xFFFFFFFFu;
  uc_reg_write(uc_, UC_ARM_REG_SP, &sp);
  uc_reg_write(uc_, UC_ARM_REG_PC, &pc);
  uc_reg_write(uc_, UC_ARM_REG_XPSR, &xpsr);
  uc_reg_write(uc_, UC_ARM_REG_PRIMASK, &zero);
  uc_reg_write(uc_, UC_ARM_REG_CONTROL, &zero);
  uc_reg_write(uc_, UC_ARM_REG_LR, &lr);
}

std::string Chip::resume() {
  return go(reg(UC_ARM_REG_PC), false);
}

std::uint32_t Chip::reg(int r) {
  std::uint32_t v = 0;
  uc_reg_read(uc_, r, &v);
  return v;
}

std::vector<std::uint32_t> Chip::writes_to(std::uint32_t address) const {
  std::vector<std::uint32_t> out;
  for (const auto& [a, v] : writes_)
    if (a == address) out.push_back(v);
  return out;
}

std::string Chip::go(std::uint32_t pc, bool until_trampoline) {
  skip_stop_ = pc & ~1u;
  stopped_at_ = "no stop";
  for (std::uint64_t slice = 0; slice < kMaxSlices; ++slice) {
    stopped_ = false;
    const uc_err err = uc_emu_start(uc_, pc | 1u, 0, 0, kSlice);
    if (!error_.empty()) return "error: " + error_;
    if (reset_requested_) return "error: SYSRESETREQ outside the main loop (not modelled)";
    if (iwdg_expired_) return "error: a watchdog reset outside the main loop (not modelled)";
    if (err != UC_ERR_OK) return std::string("error: unicorn: ") + uc_strerror(err);
    if (stopped_) {
      if (!until_trampoline || stopped_at_ == "return") return stopped_at_;
      return "error: stopped at " + stopped_at_ + " inside a handler";
    }
    cycles_ += kSlice;
    run_hardware_until(cycles_);
    if (!error_.empty()) return "error: " + error_;
    pc = reg(UC_ARM_REG_PC);
  }
  return "error: no stop within the instruction budget";
}

std::string Chip::run_for(std::uint64_t cycles) {
  const std::uint64_t end = cycles_ + cycles;
  std::uint32_t pc = reg(UC_ARM_REG_PC);
  skip_stop_ = pc & ~1u;
  while (error_.empty() && cycles_ < end) {
    const bool masked = reg(UC_ARM_REG_PRIMASK) != 0;
    if (sleeping_) {
      // PM0214 3.12.10: WFI ends on a pending exception, taken unless PRIMASK
      // is set (then the core goes on after the wfi without it).
      const int exception = deliverable_exception();
      if (exception >= 0) {
        sleeping_ = false;
        if (!masked && !take_exception(exception)) break;
        continue;
      }
      cycles_ = std::max(cycles_, std::min(next_hardware_event(), end));
      run_hardware_until(cycles_);
      if (iwdg_expired_) {
        system_reset(true);
        pc = reg(UC_ARM_REG_PC);
        skip_stop_ = 0;
      }
      continue;
    }
    // Not inside an IT block (xPSR ICI/IT 26:25, 15:10): Unicorn's slices end
    // after a whole block; this only makes sure.
    const bool in_it_block = (reg(UC_ARM_REG_XPSR) & 0x0600FC00u) != 0;
    if (!masked && !in_it_block) {
      const int exception = deliverable_exception();
      if (exception >= 0) {
        if (!take_exception(exception)) break;
        continue;
      }
    }
    stopped_ = false;
    if ((read_word(pc & ~3u) >> (8 * (pc & 2u))) % 0x10000u == kBranchToSelf) {
      // `b .` (an image hung at its reset handler, a fault loop): nothing
      // changes until a hardware event, so the chip skips time to it.
      cycles_ = std::max(cycles_, std::min(next_hardware_event(), end));
      run_hardware_until(cycles_);
    } else {
      const std::uint64_t slice = std::min<std::uint64_t>(kSlice, end - cycles_);
      const uc_err err = uc_emu_start(uc_, pc | 1u, 0, 0, slice);
      if (!error_.empty()) break;
      if (err != UC_ERR_OK) return std::string("error: unicorn: ") + uc_strerror(err);
      cycles_ += slice;
      run_hardware_until(cycles_);
    }
    if (reset_requested_ || iwdg_expired_) {
      system_reset(iwdg_expired_);
      pc = reg(UC_ARM_REG_PC);
      skip_stop_ = 0;
      continue;
    }
    pc = reg(UC_ARM_REG_PC);
    if (stopped_) {
      if (stopped_at_ != "wfi") {  // stop_at's stops end run() and resume() only
        skip_stop_ = pc;
        continue;
      }
      sleeping_ = true;  // the core sleeps in the wfi; it goes on after it
      pc += 2;
      uc_reg_write(uc_, UC_ARM_REG_PC, &pc);
    }
  }
  if (!error_.empty()) return "error: " + error_;
  return "ran";
}

bool Chip::take_exception(int exception) {
  // PM0214 2.3.7: xPSR, PC, LR, R12, R3..R0 stacked on the current stack (MSP),
  // aligned to 8 bytes (xPSR bit 9 records the padding); the handler from the
  // vector table at VTOR, entry `exception`.
  if (exception == 15)
    systick_pending_ = false;
  else
    nvic_pending_[(exception - 16) / 32] &= ~(1u << ((exception - 16) % 32));
  std::uint32_t sp = reg(UC_ARM_REG_SP);
  const bool pad = (sp & 4u) != 0;
  sp = (sp - 32 - (pad ? 4 : 0)) & ~7u;
  const std::uint32_t xpsr = (reg(UC_ARM_REG_XPSR) & ~0x1FFu & ~(1u << 9)) | 0x01000000u;
  const std::uint32_t frame[8] = {
      reg(UC_ARM_REG_R0),  reg(UC_ARM_REG_R1), reg(UC_ARM_REG_R2), reg(UC_ARM_REG_R3),
      reg(UC_ARM_REG_R12), reg(UC_ARM_REG_LR), reg(UC_ARM_REG_PC), xpsr | (pad ? 1u << 9 : 0u)};
  for (int k = 0; k < 8; ++k) write_word(sp + 4 * static_cast<std::uint32_t>(k), frame[k]);
  const std::uint32_t vector = read_word(regs_.at(kScsBase + kScbVtor) + 4 * exception);
  const std::string name = "exception " + std::to_string(exception);
  if ((vector & 1u) == 0) {
    fail("vector of " + name + " is not a Thumb address");
    return false;
  }
  const std::uint32_t lr = kTrampoline | 1u;  // stands for EXC_RETURN 0xFFFFFFF9
  uc_reg_write(uc_, UC_ARM_REG_SP, &sp);
  uc_reg_write(uc_, UC_ARM_REG_LR, &lr);
  const std::string out = go(vector, true);
  if (out != "return") {
    if (error_.empty()) fail(name + ": " + out);
    return false;
  }
  if (reg(UC_ARM_REG_SP) != sp) {
    fail(name + " left SP unbalanced");
    return false;
  }
  static constexpr int kFrameRegs[7] = {UC_ARM_REG_R0,  UC_ARM_REG_R1, UC_ARM_REG_R2, UC_ARM_REG_R3,
                                        UC_ARM_REG_R12, UC_ARM_REG_LR, UC_ARM_REG_PC};
  for (int k = 0; k < 7; ++k) {
    const std::uint32_t v = read_word(sp + 4 * static_cast<std::uint32_t>(k));
    uc_reg_write(uc_, kFrameRegs[k], &v);
  }
  const std::uint32_t stacked_xpsr = read_word(sp + 28) & ~(1u << 9);
  uc_reg_write(uc_, UC_ARM_REG_XPSR, &stacked_xpsr);
  const std::uint32_t restored = sp + 32 + (pad ? 4 : 0);
  uc_reg_write(uc_, UC_ARM_REG_SP, &restored);
  return true;
}

std::uint32_t Chip::exception_priority(int exception) const {
  // PM0214 4.3.7 / 4.4.8: one byte per exception (IPR for IRQs, SHPR3 31:24 for SysTick).
  const std::uint32_t address =
      exception == 15 ? kScsBase + 0xD20 + 3 : kScsBase + 0x400 + (exception - 16);
  return (regs_.at(address & ~3u) >> (8 * (address & 3u))) & 0xFFu;
}

int Chip::deliverable_exception() {
  if (otg_.interrupt_line()) pend(kIrqOtgFs);  // level-sensitive: pends while high
  int best = systick_pending_ ? 15 : -1;
  for (int irq = 0; irq < 96; ++irq) {
    const std::uint32_t bit = 1u << (irq % 32);
    if ((nvic_pending_[irq / 32] & bit) == 0 || (nvic_enabled_[irq / 32] & bit) == 0) continue;
    if (best < 0 || exception_priority(16 + irq) < exception_priority(best)) best = 16 + irq;
  }
  return best;
}

void Chip::pend(int irq) {
  nvic_pending_[irq / 32] |= 1u << (irq % 32);
}

// ---------------------------------------------------------------------------
// Timers and DMA

std::uint32_t Chip::tim2_count() const {
  const std::uint32_t cr1 = regs_.at(kTim2Base + kTimCr1);
  if ((cr1 & kCr1Cen) == 0) return regs_.at(kTim2Base + kTimCnt);
  const std::uint64_t ticks = (cycles_ - tim2_start_) / 2;  // APB1 timer clock: 84 MHz
  const std::uint64_t psc = regs_.at(kTim2Base + kTimPsc) + 1ull;
  return static_cast<std::uint32_t>(tim2_count0_ + ticks / psc);
}

void Chip::tim1_start(std::uint64_t at) {
  const std::uint64_t psc = regs_.at(kTim1Base + kTimPsc) + 1ull;
  const std::uint32_t arr = regs_.at(kTim1Base + kTimArr);
  const std::uint32_t cnt = regs_.at(kTim1Base + kTimCnt);
  // Upcounting (CR1 DIR 0): the update at the tick after CNT == ARR.
  const std::uint64_t ticks = cnt <= arr ? arr - cnt + 1ull : 0x10000ull - cnt + arr + 1ull;
  tim1_next_update_ = at + ticks * psc;
}

void Chip::tim1_update(std::uint64_t at) {
  const std::uint64_t psc = regs_.at(kTim1Base + kTimPsc) + 1ull;
  const std::uint64_t arr = regs_.at(kTim1Base + kTimArr);
  tim1_next_update_ = at + (arr + 1) * psc;
  regs_[kTim1Base + kTimCnt] = 0;
  regs_[kTim1Base + kTimSr] |= kSrUif;
  const std::uint32_t dier = regs_.at(kTim1Base + kTimDier);
  if ((dier & kDierUie) != 0) fail("TIM1 update interrupt (not modelled)");
  if ((dier & kDierUde) != 0) dma_request(at);
}

void Chip::dma_enable(std::uint32_t cr) {
  if ((cr & kDmaCrModelledMask) != kDmaCrModelled) {
    char b[80];
    std::snprintf(b, sizeof b, "DMA2 stream 5 configuration 0x%08x (not modelled)", cr);
    fail(b);
    return;
  }
  if ((regs_.at(kDma2Base + kDmaHisr) & (0x3Du << 6)) != 0) {
    fail("DMA2 stream 5 enabled with its flags not cleared (RM0090 10.3.17)");
    return;
  }
  dma_index_ = 0;
  dma_total_ = regs_.at(kDma2Base + kS5Ndtr) & 0xFFFFu;
  if (dma_total_ == 0) fail("DMA2 stream 5 enabled with NDTR 0");
}

void Chip::dma_request(std::uint64_t at) {
  std::uint32_t& cr = regs_[kDma2Base + kS5Cr];
  if ((cr & kDmaCrEn) == 0) return;  // no stream listening: the request is lost
  const std::uint32_t source = regs_.at(kDma2Base + kS5M0ar) + 4 * dma_index_;
  const std::uint32_t target = regs_.at(kDma2Base + kS5Par);
  if (source < kSramBase || source + 4 > kSramBase + kSramSize) {
    char b[64];
    std::snprintf(b, sizeof b, "DMA2 read of 0x%08x (not SRAM)", source);
    fail(b);
    return;
  }
  if (target != kGpioCBase + kGpioBsrr) {
    char b[64];
    std::snprintf(b, sizeof b, "DMA2 write to 0x%08x (not modelled)", target);
    fail(b);
    return;
  }
  std::uint32_t word = 0;
  uc_mem_read(uc_, source, &word, 4);
  apply_bsrr(kGpioCBase, word, at, true);
  ++dma_index_;
  std::uint32_t& ndtr = regs_[kDma2Base + kS5Ndtr];
  ndtr = dma_total_ - dma_index_;
  std::uint32_t& hisr = regs_[kDma2Base + kDmaHisr];
  if (dma_index_ == dma_total_ / 2) hisr |= kS5FlagHt;
  if (ndtr == 0) {
    hisr |= kS5FlagTc;
    cr &= ~kDmaCrEn;
    if ((cr & kDmaCrTcie) != 0) pend(kIrqDma2Stream5);
  }
}

void Chip::apply_bsrr(std::uint32_t base, std::uint32_t value, std::uint64_t at, bool by_dma) {
  // RM0090 8.4.7: a set bit wins over the reset bit of the same pin.
  std::uint32_t& odr = regs_[base + kGpioOdr];
  odr = (odr & ~(value >> 16)) | (value & 0xFFFFu);
  if (base == kGpioCBase) gpioc_writes_.push_back({at, by_dma, value, odr});
}

std::uint64_t Chip::next_hardware_event() const {
  const std::uint64_t tim1 =
      (regs_.at(kTim1Base + kTimCr1) & kCr1Cen) != 0 ? tim1_next_update_ : kNever;
  return std::min({tim1, systick_zero_, iwdg_zero_});
}

void Chip::run_hardware_until(std::uint64_t cycle) {
  while (error_.empty()) {
    const std::uint64_t next = next_hardware_event();
    if (next > cycle) return;
    if (next == iwdg_zero_) {
      // RM0090 21.3.2: the down-counter reached 0 without a reload: reset.
      iwdg_zero_ = kNever;
      iwdg_expired_ = true;
      return;
    }
    if (next == systick_zero_) {
      // PM0214 4.4: at 0 the counter reloads from LOAD (LOAD + 1 cycles a
      // period) and sets COUNTFLAG; TICKINT pends the SysTick exception.
      std::uint32_t& ctrl = regs_[kScsBase + 0x10];
      ctrl |= 1u << 16;
      if ((ctrl & 0x2u) != 0) systick_pending_ = true;
      systick_zero_ = next + (regs_.at(kScsBase + 0x14) & 0xFFFFFFu) + 1;
    } else {
      tim1_update(next);
    }
  }
}

std::uint32_t Chip::flash_sector_base(int sector) {
  // RM0090 table 5 (1 MiB part): sectors 0-3 16 KiB, 4 64 KiB, 5-11 128 KiB.
  if (sector < 4) return kFlashBase + 0x4000u * static_cast<std::uint32_t>(sector);
  if (sector == 4) return kFlashBase + 0x10000u;
  return kFlashBase + 0x20000u * static_cast<std::uint32_t>(sector - 4);
}

void Chip::flash_control(std::uint32_t value) {
  std::uint32_t& cr = regs_[kFlashCr];
  if ((cr & kCrLock) != 0) {
    if ((value | kCrLock) == (cr | kCrLock)) return;  // setting LOCK again: nothing changes
    fail("write of FLASH_CR while LOCK is set (ignored by the chip)");
    return;
  }
  if ((value & ~kCrModelled) != 0 || (value & kCrMer) != 0) {
    fail("FLASH_CR: mass erase or interrupts (not modelled)");
    return;
  }
  if ((value & (kCrPg | kCrSer)) != 0 && (value & kCrPsizeMask) != kCrPsizeX32) {
    fail("FLASH_CR: a parallelism other than x32 (not modelled)");
    return;
  }
  if (flash_busy_reads_ > 0 && value != cr) {
    fail("FLASH_CR written while BSY (RM0090 3.9.8)");
    return;
  }
  cr = value & ~kCrStrt;  // STRT clears itself as the erase ends
  if ((value & kCrStrt) == 0) return;
  if ((value & kCrSer) == 0) {
    fail("FLASH_CR.STRT without SER (not modelled)");
    return;
  }
  const int sector = static_cast<int>((value >> 3) & 0xFu);
  if (sector > 11) {
    fail("FLASH_CR: sector number beyond the part");
    return;
  }
  if ((regs_.at(kFlashOptcr) & (1u << (16 + sector))) == 0) {  // nWRP: 0 = protected
    regs_[kFlashSr] |= kSrWrperr;
    return;
  }
  const std::uint32_t base = flash_sector_base(sector);
  const std::vector<std::uint8_t> erased(flash_sector_base(sector + 1) - base, 0xFF);
  uc_mem_write(uc_, base, erased.data(), erased.size());
  // Code translated from the old contents must not run again (guest stores
  // while programming invalidate it themselves; this write is the model's).
  uc_ctl_remove_cache(uc_, base, base + static_cast<std::uint32_t>(erased.size()));
  flash_erases_.push_back(sector);
  flash_busy_reads_ = 3;
  regs_[kFlashSr] |= 1u;  // EOP
}

void Chip::flash_store(uc_engine*, uc_mem_type, std::uint64_t address, int size, std::int64_t value,
                       void* user) {
  // RM0090 3.6.4: with PG set and x32 parallelism, one aligned word per write;
  // programming can only clear bits (the firmware erases first).
  auto* chip = static_cast<Chip*>(user);
  const std::uint32_t cr = chip->regs_.at(kFlashCr);
  char b[112];
  if ((cr & kCrLock) != 0 || (cr & kCrPg) == 0 || chip->flash_busy_reads_ > 0) {
    std::snprintf(b, sizeof b, "write to flash at 0x%08llx without FLASH_CR.PG (or locked, busy)",
                  static_cast<unsigned long long>(address));
    chip->fail(b);
    return;
  }
  const int sector = [&] {
    int s = 0;
    while (s < 11 && address >= chip->flash_sector_base(s + 1)) ++s;
    return s;
  }();
  if (size != 4 || address % 4 != 0 || (chip->regs_.at(kFlashOptcr) & (1u << (16 + sector))) == 0) {
    std::snprintf(b, sizeof b, "flash program of %d bytes at 0x%08llx (unaligned or protected)",
                  size, static_cast<unsigned long long>(address));
    chip->fail(b);
    return;
  }
  const std::uint32_t old = chip->read_word(static_cast<std::uint32_t>(address));
  const auto word = static_cast<std::uint32_t>(value);
  if ((old & word) != word) {
    std::snprintf(b, sizeof b, "flash program of 0x%08x over 0x%08x at 0x%08llx (not erased)", word,
                  old, static_cast<unsigned long long>(address));
    chip->fail(b);
    return;
  }
  ++chip->flash_programs_;
  chip->flash_busy_reads_ = 1;
}

void Chip::systick_store(std::uint32_t address, std::uint32_t value) {
  std::uint32_t& ctrl = regs_[kScsBase + 0x10];
  if (address == kScsBase + 0x10) {
    if ((value & 0x1u) != 0 && (value & 0x4u) == 0) {
      fail("SysTick on the external reference clock (CLKSOURCE 0; not modelled)");
      return;
    }
    const bool start = (ctrl & 0x1u) == 0 && (value & 0x1u) != 0;
    ctrl = (ctrl & (1u << 16)) | (value & 0x7u);
    if ((value & 0x1u) == 0) systick_zero_ = kNever;
    // From VAL: 0 reloads at the next cycle, then counts LOAD down.
    const std::uint32_t val = regs_.at(kScsBase + 0x18);
    if (start)
      systick_zero_ = cycles_ + (val != 0 ? val : (regs_.at(kScsBase + 0x14) & 0xFFFFFFu) + 1);
  } else if (address == kScsBase + 0x14) {
    regs_[address] = value & 0xFFFFFFu;
  } else if (address == kScsBase + 0x18) {  // any write clears VAL and COUNTFLAG
    regs_[address] = 0;
    ctrl &= ~(1u << 16);
    if ((ctrl & 0x1u) != 0) systick_zero_ = cycles_ + (regs_.at(kScsBase + 0x14) & 0xFFFFFFu) + 1;
  } else {
    fail("write of SysTick CALIB (read-only)");
  }
}

void Chip::strobe_pin(bool level) {
  if (level == strobe_level_) return;
  strobe_level_ = level;
  const std::uint32_t ccmr1 = regs_.at(kTim2Base + kTimCcmr1);
  const std::uint32_t ccer = regs_.at(kTim2Base + kTimCcer);
  std::uint32_t& sr = regs_[kTim2Base + kTimSr];
  const std::uint32_t dier = regs_.at(kTim2Base + kTimDier);
  const std::uint32_t count = tim2_count();
  // CC1S = 01 (IC1 on TI1), CC2S = 10 (IC2 on TI1): RM0090 18.4.7.
  const bool ch1_on_ti1 = (ccmr1 & 0x3u) == 0x1u;
  const bool ch2_on_ti1 = ((ccmr1 >> 8) & 0x3u) == 0x2u;
  for (int ch = 1; ch <= 2; ++ch) {
    const std::uint32_t bits = ccer >> (4 * (ch - 1));
    const bool enabled = (bits & 1u) != 0 && (ch == 1 ? ch1_on_ti1 : ch2_on_ti1);
    const bool falling = (bits & 2u) != 0;  // CCxP (CCxNP 0: one edge)
    if (!enabled || falling == level) continue;
    const std::uint32_t flag = ch == 1 ? kSrCc1If : kSrCc2If;
    if ((sr & flag) != 0) sr |= ch == 1 ? kSrCc1Of : kSrCc2Of;
    sr |= flag;
    regs_[kTim2Base + (ch == 1 ? kTimCcr1 : kTimCcr2)] = count;
    if ((dier & (ch == 1 ? kDierCc1Ie : kDierCc2Ie)) != 0) pend(kIrqTim2);
    // MMS = 011 (compare pulse): TRGO pulses as CC1IF is set.
    const std::uint32_t mms = (regs_.at(kTim2Base + kTimCr2) >> 4) & 0x7u;
    if (ch == 1 && mms == 0x3u) {
      // TIM1: SMS = 110 (trigger mode), TS = 001 (ITR1 = TIM2 TRGO, RM0090 table 86).
      const std::uint32_t smcr = regs_.at(kTim1Base + kTimSmcr);
      if ((smcr & 0x7u) == 0x6u && ((smcr >> 4) & 0x7u) == 0x1u) {
        std::uint32_t& cr1 = regs_[kTim1Base + kTimCr1];
        regs_[kTim1Base + kTimSr] |= kSrTif;
        if ((cr1 & kCr1Cen) == 0) {
          cr1 |= kCr1Cen;
          tim1_start(cycles_);
        }
      } else if ((smcr & 0x7u) != 0) {
        fail("TIM1 slave mode other than trigger from ITR1 (not modelled)");
      }
    }
  }
}

// ---------------------------------------------------------------------------
// Registers

void Chip::map_region(std::uint32_t base, std::uint32_t size) {
  regions_.push_back(std::make_unique<Region>(Region{this, base}));
  Region* r = regions_.back().get();
  if (uc_mmio_map(uc_, base, size, &Chip::mmio_read, r, &Chip::mmio_write, r) != UC_ERR_OK)
    fail("uc_mmio_map");
}

void Chip::model_registers() {
  auto block = [this](std::uint32_t base, std::uint32_t last_offset) {
    for (std::uint32_t o = 0; o <= last_offset; o += 4) regs_[base + o] = 0;
  };
  // RCC (RM0090 7.3): CR HSION|HSIRDY, PLLCFGR, AHB1ENR CCMDATARAMEN, CSR POR|PIN|BOR.
  for (const std::uint32_t o :
       {0x00u, 0x04u, 0x08u, 0x0Cu, 0x10u, 0x14u, 0x18u, 0x20u, 0x24u, 0x30u, 0x34u, 0x38u,
        0x40u, 0x44u, 0x50u, 0x54u, 0x58u, 0x60u, 0x64u, 0x70u, 0x74u, 0x80u, 0x84u})
    regs_[kRccBase + o] = 0;
  regs_[kRccBase + 0x00] = 0x00000083;
  regs_[kRccBase + 0x04] = 0x24003010;
  regs_[kRccBase + 0x30] = 0x00100000;
  regs_[kRccBase + 0x74] = 0x0E000000;
  block(kFlashIfBase, 0x14);  // ACR, KEYR, OPTKEYR, SR, CR, OPTCR
  regs_[kFlashIfBase + 0x10] = 0x80000000;
  regs_[kFlashOptcr] = kFactoryOptcr;
  block(kPwrBase, 0x04);
  for (const std::uint32_t gpio : {kGpioABase, kGpioBBase, kGpioCBase}) block(gpio, 0x24);
  regs_[kGpioABase + 0x00] = 0xA8000000;
  regs_[kGpioABase + 0x08] = 0x0C000000;
  regs_[kGpioABase + 0x0C] = 0x64000000;
  regs_[kGpioBBase + 0x00] = 0x00000280;
  regs_[kGpioBBase + 0x08] = 0x000000C0;
  regs_[kGpioBBase + 0x0C] = 0x00000100;
  for (const std::uint32_t tim : {kTim1Base, kTim2Base, kTim3Base, kTim5Base}) block(tim, 0x50);
  regs_[kTim1Base + kTimArr] = 0xFFFF;
  regs_[kTim2Base + kTimArr] = 0xFFFFFFFF;
  block(kDma2Base, 0xCC);  // LISR..HIFCR, streams 0..7
  block(kIwdgBase, 0x0C);
  regs_[kIwdgBase + 0x08] = 0x00000FFF;
  block(kDbgmcuBase, 0x0C);
  // System control space (PM0214 4): SysTick, NVIC, SCB.
  for (std::uint32_t o = 0x10; o <= 0x1C; o += 4) regs_[kScsBase + o] = 0;
  for (std::uint32_t o = 0x100; o <= 0x29C; o += 4) regs_[kScsBase + o] = 0;
  for (std::uint32_t o = 0x400; o <= 0x4EC; o += 4) regs_[kScsBase + o] = 0;
  for (std::uint32_t o = 0xD00; o <= 0xD24; o += 4) regs_[kScsBase + o] = 0;
  regs_[kScsBase + 0xD00] = 0x410FC241;  // CPUID: Cortex-M4 r0p1
  regs_[kScsBase + kScbCpacr] = 0;
  // The 96-bit unique ID (RM0090 39.1), read-only.
  // OTP (RM0090 3.8), erased; programmed through the flash interface (store).
  for (std::uint32_t a = kOtpBase; a < kOtpBase + kOtpSize; a += 4) regs_[a] = 0xFFFFFFFFu;
  regs_[kUniqueIdPage + 0xA10] = 0x00470031;
  regs_[kUniqueIdPage + 0xA14] = 0x31385119;
  regs_[kUniqueIdPage + 0xA18] = 0x32363734;
}

bool Chip::nvic_observe(std::uint32_t offset, std::uint32_t* value) const {
  for (const std::uint32_t base : {kIser, kIcer, kIspr, kIcpr})
    if (offset >= base && offset < base + 12) {
      const std::uint32_t word = (offset - base) / 4;
      *value = base == kIser || base == kIcer ? nvic_enabled_[word] : nvic_pending_[word];
      return true;
    }
  return false;
}

void Chip::nvic_store(std::uint32_t offset, std::uint32_t value) {
  auto in = [offset](std::uint32_t base) { return offset >= base && offset < base + 12; };
  if (in(kIser)) nvic_enabled_[(offset - kIser) / 4] |= value;
  if (in(kIcer)) nvic_enabled_[(offset - kIcer) / 4] &= ~value;
  if (in(kIspr)) nvic_pending_[(offset - kIspr) / 4] |= value;
  if (in(kIcpr)) nvic_pending_[(offset - kIcpr) / 4] &= ~value;
}

std::uint32_t Chip::observe(std::uint32_t address) {
  std::uint32_t v = regs_.at(address);
  if (address == kRccBase + 0x00) {  // CR: each oscillator / the PLL ready once on
    if (v & (1u << 0)) v |= 1u << 1;
    if (v & (1u << 16)) v |= 1u << 17;
    if (v & (1u << 24)) v |= 1u << 25;
  } else if (address == kRccBase + 0x08) {  // CFGR: SWS follows SW
    v = (v & ~0xCu) | ((v & 0x3u) << 2);
  } else if (address == kGpioBBase + kGpioIdr) {  // PB2: the recovery jumper, else pulled down
    v = recovery_pin_high ? (1u << 2) : 0u;
  } else if (address == kGpioABase + kGpioIdr) {  // PA5: the strobe input (TIM2_CH1)
    v = strobe_level_ ? 1u << 5 : 0u;
  } else if (address == kGpioCBase + kGpioIdr) {
    v = 0;
  } else if (address == kTim2Base + kTimCnt) {
    v = tim2_count();
  } else if (address == kTim2Base + kTimCcr1) {  // reading CCRx clears CCxIF (RM0090 18.4.5)
    regs_[kTim2Base + kTimSr] &= ~kSrCc1If;
  } else if (address == kTim2Base + kTimCcr2) {
    regs_[kTim2Base + kTimSr] &= ~kSrCc2If;
  } else if (address == kTim1Base + kTimCnt && (regs_.at(kTim1Base + kTimCr1) & kCr1Cen) != 0) {
    fail("read of TIM1_CNT while counting (not modelled)");
  } else if (address == kFlashSr) {
    if (flash_busy_reads_ > 0) {
      --flash_busy_reads_;
      v |= kFlashSrBsy;
    }
  } else if (address >= kScsBase + 0x100 && address < kScsBase + 0x300) {
    nvic_observe(address - kScsBase, &v);
  } else if (address == kScsBase + 0x10) {  // reading CTRL clears COUNTFLAG
    regs_[address] &= ~(1u << 16);
  } else if (address == kScsBase + 0x18 && (regs_.at(kScsBase + 0x10) & 0x1u) != 0) {
    fail("read of SysTick VAL while counting (not modelled)");
  }
  return v;
}

void Chip::iwdg_store(std::uint32_t offset, std::uint32_t value) {
  // RM0090 21.4: KR 0xCCCC starts the counter (and the LSI), 0xAAAA reloads it
  // from RLR, 0x5555 opens PR and RLR to writes (any other key closes them);
  // SR's PVU/RVU read 0 (updates take effect at once). Timeout: 4 x 2^PR x
  // (RLR + 1) LSI cycles at the nominal 32 kHz, in 168 MHz core cycles.
  if (offset == 0x00) {
    const std::uint32_t key = value & 0xFFFFu;
    iwdg_unlocked_ = key == 0x5555u;
    const bool start = key == 0xCCCCu;
    if (start || (key == 0xAAAAu && iwdg_zero_ != kNever)) {
      const std::uint64_t lsi_ticks = (4ull << (regs_.at(kIwdgBase + 0x04) & 7u)) *
                                      ((regs_.at(kIwdgBase + 0x08) & 0xFFFu) + 1);
      iwdg_zero_ = cycles_ + lsi_ticks * (kCpuHz / kLsiHz);
    }
    return;
  }
  if ((offset == 0x04 || offset == 0x08) && iwdg_unlocked_)
    regs_[kIwdgBase + offset] = value & (offset == 0x04 ? 7u : 0xFFFu);
}

void Chip::store(std::uint32_t address, std::uint32_t value) {
  writes_.push_back({address, value});
  const std::uint32_t offset = address & 0x3FFu;
  const std::uint32_t base = address & ~0x3FFu;
  if (base == kIwdgBase) {
    iwdg_store(offset, value);
    return;
  }
  if (address >= kOtpBase && address < kOtpBase + kOtpSize) {
    // RM0090 3.8: OTP is programmed like main flash (PG, x32 here) and never erased.
    const std::uint32_t cr = regs_.at(kFlashCr);
    const std::uint32_t old = regs_.at(address);
    if ((cr & kCrLock) != 0 || (cr & kCrPg) == 0 || flash_busy_reads_ > 0 || (old & value) != value) {
      char b[96];
      std::snprintf(b, sizeof b, "OTP program of 0x%08x over 0x%08x at 0x%08x (no PG or not erased)",
                    value, old, address);
      fail(b);
      return;
    }
    regs_[address] = value;
    ++otp_programs_;
    flash_busy_reads_ = 1;
    return;
  }
  if (address == kRccBase + 0x74 && (value & (1u << 24)) != 0) {  // CSR.RMVF
    regs_[address] = regs_[address] & 0x00FFFFFFu;
    return;
  }
  if ((base == kGpioABase || base == kGpioBBase || base == kGpioCBase) && offset == kGpioBsrr) {
    apply_bsrr(base, value, cycles_, false);  // BSRR reads 0
    return;
  }
  if (base == kTim1Base || base == kTim2Base) {
    std::uint32_t& cr1 = regs_[base + kTimCr1];
    const bool running = (cr1 & kCr1Cen) != 0;
    if (offset == kTimSr) {  // rc_w0: writing 0 clears a flag, 1 leaves it
      regs_[address] &= value;
      return;
    }
    if (offset == kTimEgr) {  // UG: counter and prescaler reinitialised
      if ((value & kEgrUg) != 0) {
        if (base == kTim2Base && running) {
          fail("TIM2 UG while counting (not modelled)");
          return;
        }
        regs_[base + kTimCnt] = 0;
        if ((cr1 & kCr1Urs) == 0 && (regs_.at(base + kTimDier) & kDierUde) != 0)
          fail("an update request from UG (URS 0) (not modelled)");
        if (base == kTim1Base && running) tim1_start(cycles_);
      }
      return;
    }
    if (offset == kTimCnt && running) {
      fail(base == kTim1Base ? "write of TIM1_CNT while counting (not modelled)"
                             : "write of TIM2_CNT while counting (not modelled)");
      return;
    }
    if (offset == kTimCr1) {
      const bool start = !running && (value & kCr1Cen) != 0;
      const bool stop = running && (value & kCr1Cen) == 0;
      if (base == kTim2Base && stop) tim2_count0_ = tim2_count();
      regs_[address] = value;
      if (base == kTim1Base && start) tim1_start(cycles_);
      if (base == kTim2Base && start) {
        tim2_start_ = cycles_;
        tim2_count0_ = regs_.at(kTim2Base + kTimCnt);
      }
      if (base == kTim2Base && stop) regs_[kTim2Base + kTimCnt] = tim2_count0_;
      return;
    }
    if (base == kTim1Base && running && (offset == kTimPsc || offset == kTimArr)) {
      fail("TIM1 PSC/ARR written while counting (not modelled)");
      return;
    }
  }
  if (base == kDma2Base) {
    if (offset == kDmaLisr || offset == kDmaHisr) {
      fail("write of a read-only DMA2 status register");
      return;
    }
    if (offset == kDmaLifcr || offset == kDmaHifcr) {  // write 1 to clear
      regs_[kDma2Base + (offset == kDmaLifcr ? kDmaLisr : kDmaHisr)] &= ~value;
      return;
    }
    const bool enabled = (regs_.at(kDma2Base + kS5Cr) & kDmaCrEn) != 0;
    if (offset == kS5Cr) {
      regs_[address] = value;
      if (!enabled && (value & kDmaCrEn) != 0) dma_enable(value);
      return;  // EN cleared by the core: the stream stops (it moves one word at a time)
    }
    if (enabled &&
        (offset == kS5Ndtr || offset == kS5Par || offset == kS5M0ar || offset == kS5Fcr)) {
      fail("DMA2 stream 5 configured while enabled (RM0090 10.5.5: ignored; not modelled)");
      return;
    }
    if (offset < kS5 || offset > kS5Fcr) {
      if (value != 0) fail("DMA2: a stream other than 5 configured (not modelled)");
      return;
    }
  }
  if (address == kFlashKeyr) {
    const std::uint32_t expected = flash_key_step_ == 0 ? kKey1 : kKey2;
    if (value != expected) {
      fail("wrong FLASH_KEYR sequence (RM0090 3.6.1: FLASH_CR locks until reset)");
      return;
    }
    if (++flash_key_step_ == 2) {
      flash_key_step_ = 0;
      regs_[kFlashCr] &= ~kCrLock;
    }
    return;
  }
  if (address == kFlashSr) {  // rc_w1 flags; BSY read-only
    regs_[address] &= ~(value & kSrFlags);
    return;
  }
  if (address == kFlashCr) {
    flash_control(value);
    return;
  }
  if (address == kFlashOptKeyr) {
    const std::uint32_t expected = optkey_step_ == 0 ? kOptKey1 : kOptKey2;
    if (value != expected) {
      fail("wrong FLASH_OPTKEYR sequence (RM0090 3.6.2: the register locks until reset)");
      return;
    }
    if (++optkey_step_ == 2) {
      optkey_step_ = 0;
      regs_[kFlashOptcr] &= ~kOptcrOptLock;
    }
    return;
  }
  if (address == kFlashOptcr) {
    const std::uint32_t current = regs_.at(kFlashOptcr);
    if ((current & kOptcrOptLock) != 0) {
      fail("write of FLASH_OPTCR while OPTLOCK is set (ignored by the chip)");
      return;
    }
    if ((value & kOptcrOptStrt) != 0) {
      if (flash_busy_reads_ > 0) {
        fail("OPTSTRT while the flash is busy");
        return;
      }
      ++option_programs_;
      flash_busy_reads_ = 3;  // the option bytes are written meanwhile
      value &= ~kOptcrOptStrt;
    }
    regs_[address] = value;
    return;
  }
  if (address == kScsBase + 0xD0C) {      // AIRCR: VECTKEY 0x05FA, SYSRESETREQ (bit 2)
    if ((value >> 16) != 0x05FA) return;  // ignored without the key
    if ((value & ~(0xFFFF0000u | 1u << 2)) != 0) {
      fail("AIRCR write other than SYSRESETREQ (not modelled)");
      return;
    }
    reset_requested_ = true;
    if (uc_ != nullptr) uc_emu_stop(uc_);
    return;
  }
  if (address >= kScsBase + 0x10 && address <= kScsBase + 0x1C) {
    systick_store(address, value);
    return;
  }
  if (base == kScsBase + 0x000 && offset >= 0x100 && offset < 0x300) {
    nvic_store(offset, value);
    return;
  }
  regs_[address] = value;
}

bool Chip::clocked(std::uint32_t address) const {
  const std::uint32_t ahb1 = regs_.at(kRccBase + 0x30);
  const std::uint32_t apb1 = regs_.at(kRccBase + 0x40);
  const std::uint32_t apb2 = regs_.at(kRccBase + 0x44);
  const std::uint32_t base = address & ~0x3FFu;
  if (base == kGpioABase) return (ahb1 & (1u << 0)) != 0;
  if (base == kGpioBBase) return (ahb1 & (1u << 1)) != 0;
  if (base == kGpioCBase) return (ahb1 & (1u << 2)) != 0;
  if (base == kDma2Base) return (ahb1 & (1u << 22)) != 0;
  if (base == kTim2Base) return (apb1 & (1u << 0)) != 0;
  if (base == kTim3Base) return (apb1 & (1u << 1)) != 0;
  if (base == kTim5Base) return (apb1 & (1u << 3)) != 0;
  if (base == kPwrBase) return (apb1 & (1u << 28)) != 0;
  if (base == kTim1Base) return (apb2 & (1u << 0)) != 0;
  if (address >= OtgFs::kBase && address < OtgFs::kBase + OtgFs::kSize)
    return (regs_.at(kRccBase + 0x34) & (1u << 7)) != 0;  // AHB2ENR.OTGFSEN
  return true;
}

void Chip::fail(const std::string& what) {
  if (error_.empty()) {
    char pc[32];
    std::snprintf(pc, sizeof pc, " at pc 0x%08x", uc_ != nullptr ? reg(UC_ARM_REG_PC) : 0u);
    error_ = what + pc;
  }
  if (uc_ != nullptr) uc_emu_stop(uc_);
}

void Chip::unmodelled(const char* what, std::uint64_t address) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%s of 0x%08llx (not modelled)", what,
                static_cast<unsigned long long>(address));
  fail(buffer);
}

std::uint32_t Chip::otg_read(std::uint32_t address, unsigned size) {
  if (size != 4 || !clocked(address)) {
    unmodelled("read", address);
    return 0;
  }
  std::uint32_t v = 0;
  std::string error;
  if (!otg_.read(address - OtgFs::kBase, &v, &error)) fail(error);
  return v;
}

void Chip::otg_write(std::uint32_t address, unsigned size, std::uint32_t value) {
  if (size != 4 || !clocked(address)) {
    unmodelled("write", address);
    return;
  }
  writes_.push_back({address, value});
  std::string error;
  if (!otg_.write(address - OtgFs::kBase, value, &error)) fail(error);
}

bool Chip::check(std::uint32_t word, const char* what, std::uint32_t address) {
  if (regs_.count(word) == 0 || !clocked(word)) {
    unmodelled(what, address);  // a peripheral whose clock is off ignores the bus
    return false;
  }
  return true;
}

std::uint64_t Chip::mmio_read(uc_engine*, std::uint64_t offset, unsigned size, void* user) {
  const auto* region = static_cast<const Region*>(user);
  Chip* chip = region->chip;
  const std::uint32_t address = region->base + static_cast<std::uint32_t>(offset);
  const std::uint32_t word = address & ~3u;
  if (region->base == OtgFs::kBase) return chip->otg_read(address, size);
  if (!chip->check(word, "read", address)) return 0;
  const std::uint32_t v = chip->observe(word) >> (8 * (address & 3u));
  return size == 4 ? v : v & ((1u << (8 * size)) - 1u);
}

void Chip::mmio_write(uc_engine*, std::uint64_t offset, unsigned size, std::uint64_t value,
                      void* user) {
  const auto* region = static_cast<const Region*>(user);
  Chip* chip = region->chip;
  const std::uint32_t address = region->base + static_cast<std::uint32_t>(offset);
  const std::uint32_t word = address & ~3u;
  if (region->base == OtgFs::kBase) {
    chip->otg_write(address, size, static_cast<std::uint32_t>(value));
    return;
  }
  if (!chip->check(word, "write", address)) return;
  std::uint32_t v = static_cast<std::uint32_t>(value);
  if (size != 4) {  // a byte or half-word: the other lanes keep their value
    const std::uint32_t shift = 8 * (address & 3u);
    const std::uint32_t mask = ((size == 1 ? 0xFFu : 0xFFFFu)) << shift;
    v = (chip->regs_.at(word) & ~mask) | ((v << shift) & mask);
  }
  chip->store(word, v);
}

bool Chip::unmapped(uc_engine*, uc_mem_type type, std::uint64_t address, int, std::int64_t,
                    void* user) {
  static_cast<Chip*>(user)->unmodelled(type == UC_MEM_WRITE_UNMAPPED   ? "write"
                                       : type == UC_MEM_FETCH_UNMAPPED ? "fetch"
                                                                       : "read",
                                       address);
  return false;
}

void Chip::on_code(uc_engine* uc, std::uint64_t address, std::uint32_t, void* user) {
  auto* chip = static_cast<Chip*>(user);
  if (address == chip->skip_stop_) {  // resuming from this stop
    chip->skip_stop_ = 0;
    return;
  }
  for (const auto& [at, name] : chip->stops_)
    if (at == address) chip->stopped_at_ = name;
  chip->stopped_ = true;
  uc_emu_stop(uc);
}

}  // namespace flutterscan::firmware::emu
