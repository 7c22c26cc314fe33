#pragma once
// The emulated STM32F405 of the emu tests: a Cortex-M4 in the Unicorn engine
// (flash, SRAM) with models of the peripherals the product images touch,
// written from RM0090 (RCC, flash interface and option bytes, PWR, GPIO,
// TIM1/TIM2/TIM3/TIM5, DMA2, IWDG, DBGMCU, OTG_FS) and PM0214 (SysTick, NVIC,
// SCB).
// Any access to a register that is not modelled, or to a peripheral whose
// clock is off, stops the emulation with an error naming the address.
//
// Time: one instruction is one cycle of the 168 MHz core clock the
// application sets up (also before it does: start-up timing is not what is
// modelled). The APB1 timers (TIM2: the microsecond clock and strobe capture)
// count at 84 MHz before their prescaler, the APB2 timer TIM1 at 168 MHz. The
// core runs in slices of kSlice instructions; between slices (and while the
// core sleeps) the timers, SysTick and DMA2 stream 5 run event by event, each event at
// its exact cycle.
//
// Modelled dynamics: TIM2 counting and input capture of the strobe pin on
// channels 1 and 2 (TI1, either polarity), with TRGO pulsing on CC1 capture
// (MMS = compare pulse); TIM1 in trigger mode from ITR1 (= TIM2 TRGO), counting
// up to ARR with update DMA requests (UDE); DMA2 stream 5 memory to peripheral,
// 32-bit, one word per request, into GPIOC BSRR, with its transfer-complete
// flag and interrupt; SysTick counting the core clock down from LOAD and
// raising its exception (PM0214 4.4); the OTG_FS core (emu_otg_fs.hpp) and its
// interrupt line; NVIC enable/pending registers and priorities (IPR, SHPR3).
//
// Exceptions: Unicorn does no Cortex-M exception entry or return, so the model
// does it (PM0214 2.3.7): the frame (R0-R3, R12, LR, PC, xPSR with its flags
// and IT state) is stacked on MSP, the handler entered through the vector
// table at VTOR and its return caught at a trampoline, which unstacks the
// frame. An exception is taken between instruction slices while PRIMASK is
// clear, and while the core sleeps in `wfi` (Chip::run_for);
// of those pending and enabled, the one with the lowest priority value, then
// the lowest number. Handlers run to completion (the product's handlers are
// short; no preemption is modelled); the image uses no floating point, so no
// FP context is stacked (a handler that used it would not be caught).

#include <unicorn/unicorn.h>

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "emu_otg_fs.hpp"

namespace flutterscan::firmware::emu {

inline constexpr std::uint32_t kFlashBase = 0x08000000;
inline constexpr std::uint32_t kFlashSize = 1024 * 1024;
inline constexpr std::uint32_t kSramBase = 0x20000000;
inline constexpr std::uint32_t kSramSize = 128 * 1024;
inline constexpr std::uint32_t kAppBase = 0x08008000;
// RM0090 2.3 memory map, 7.3 RCC, 8.4 GPIO; PM0214 4.3 SCB.
inline constexpr std::uint32_t kRccBase = 0x40023800;
inline constexpr std::uint32_t kRccAhb1Enr = 0x30;
inline constexpr std::uint32_t kFlashIfBase = 0x40023C00;
inline constexpr std::uint32_t kFlashOptKeyr = kFlashIfBase + 0x08;
inline constexpr std::uint32_t kFlashSr = kFlashIfBase + 0x0C;
inline constexpr std::uint32_t kFlashOptcr = kFlashIfBase + 0x14;
/// FLASH_OPTCR after reset with the factory option bytes (RM0090 3.9.7):
/// nWRP all 1 (no sector protected), RDP 0xAA (level 0), OPTLOCK set.
inline constexpr std::uint32_t kFactoryOptcr = 0x0FFFAAED;
inline constexpr std::uint32_t kPwrBase = 0x40007000;
inline constexpr std::uint32_t kGpioABase = 0x40020000;
inline constexpr std::uint32_t kGpioBBase = 0x40020400;
inline constexpr std::uint32_t kGpioCBase = 0x40020800;
inline constexpr std::uint32_t kGpioModer = 0x00;
inline constexpr std::uint32_t kGpioPupdr = 0x0C;
inline constexpr std::uint32_t kGpioIdr = 0x10;
inline constexpr std::uint32_t kGpioOdr = 0x14;
inline constexpr std::uint32_t kGpioBsrr = 0x18;
inline constexpr std::uint32_t kTim1Base = 0x40010000;
inline constexpr std::uint32_t kTim2Base = 0x40000000;
inline constexpr std::uint32_t kTim3Base = 0x40000400;
inline constexpr std::uint32_t kTim5Base = 0x40000C00;
inline constexpr std::uint32_t kDma2Base = 0x40026400;
inline constexpr std::uint32_t kIwdgBase = 0x40003000;
inline constexpr std::uint32_t kDbgmcuBase = 0xE0042000;
inline constexpr std::uint32_t kUniqueIdPage = 0x1FFF7000;
/// OTP area (RM0090 3.8): 16 blocks of 32 bytes, then 16 lock bytes; erased 0xFF.
inline constexpr std::uint32_t kOtpBase = 0x1FFF7800;
inline constexpr std::uint32_t kOtpSize = 528;
inline constexpr std::uint32_t kScsBase = 0xE000E000;
inline constexpr std::uint32_t kScbVtor = 0xD08;
inline constexpr std::uint32_t kScbCpacr = 0xD88;
// Timer register offsets (RM0090 17.4, 18.4).
inline constexpr std::uint32_t kTimCr1 = 0x00;
inline constexpr std::uint32_t kTimSmcr = 0x08;
inline constexpr std::uint32_t kTimSr = 0x10;
/// Device interrupts of the strobe path (RM0090 table 61).
inline constexpr int kIrqTim2 = 28;
inline constexpr int kIrqDma2Stream5 = 68;
inline constexpr int kIrqOtgFs = 67;

class Chip {
 public:
  static constexpr std::uint64_t kCpuHz = 168'000'000;
  /// The LSI clocking the IWDG, nominal (RM0090 5.2.5: 17-47 kHz).
  static constexpr std::uint64_t kLsiHz = 32'000;
  /// Thumb `b .` (branch to itself).
  static constexpr std::uint32_t kBranchToSelf = 0xE7FE;
  static constexpr std::uint64_t kCyclesPerUs = kCpuHz / 1'000'000;

  Chip();
  ~Chip();
  Chip(const Chip&) = delete;
  Chip& operator=(const Chip&) = delete;

  void write(std::uint32_t address, const std::vector<std::uint8_t>& bytes);
  void write_word(std::uint32_t address, std::uint32_t value);
  std::uint32_t read_word(std::uint32_t address);
  void stop_at(std::uint32_t address, const char* name);

  /// Resets the core (SP and PC from the vector table at 0) and runs to a stop.
  std::string run();
  /// Runs on from where the last stop was.
  std::string resume();
  /// Marks the `wfi` at `address` (the main loop's): there the core sleeps
  /// until an exception is pending (Chip::run_for).
  void sleep_at(std::uint32_t address);
  /// Runs the core on from where it is (thread mode: the main loop) for
  /// `cycles`, taking exceptions as they pend while PRIMASK is clear and
  /// sleeping in a `wfi` marked with sleep_at; a SYSRESETREQ (AIRCR) resets
  /// the chip and the core goes on from the reset vector (stops set with
  /// stop_at are passed). "ran" or the error.
  std::string run_for(std::uint64_t cycles);
  /// The strobe input (PA5, TIM2_CH1 = TI1) goes to `level`; the input
  /// filter's delay is not modelled (the capture is at the edge's cycle).
  void strobe_pin(bool level);

  std::uint64_t cycles() const { return cycles_; }
  /// System resets requested through AIRCR so far.
  int system_resets() const { return system_resets_; }
  /// The cycles at which the independent watchdog reset the chip, in order.
  const std::vector<std::uint64_t>& watchdog_resets() const { return watchdog_resets_; }
  std::uint32_t reg(int r);
  OtgFs& otg_fs() { return otg_; }
  /// A modelled peripheral register's value (as stored; no side effects).
  std::uint32_t io(std::uint32_t address) const { return regs_.at(address); }
  /// Every value written to `address` by the core, in order.
  std::vector<std::uint32_t> writes_to(std::uint32_t address) const;

  /// A write to GPIOC BSRR (by the core or by DMA2 stream 5) and ODR after it.
  struct PinWrite {
    std::uint64_t cycle;
    bool by_dma;
    std::uint32_t bsrr;
    std::uint32_t odr;
  };
  const std::vector<PinWrite>& gpioc_writes() const { return gpioc_writes_; }
  /// Sectors erased through the flash interface, in order.
  const std::vector<int>& flash_erases() const { return flash_erases_; }
  /// Words programmed through the flash interface.
  int flash_programs() const { return flash_programs_; }
  /// Words programmed into the OTP area through the flash interface.
  int otp_programs() const { return otp_programs_; }
  /// Option-byte programming operations (OPTSTRT) seen.
  int option_programs() const { return option_programs_; }
  /// Sets the option bytes the chip comes out of reset with (FLASH_OPTCR).
  void set_option_bytes(std::uint32_t optcr);
  /// Sets the reset flags RCC_CSR comes out of reset with (bits 31:25; the
  /// model's default is a power-on: PORRSTF, PINRSTF, BORRSTF).
  void set_reset_flags(std::uint32_t flags);

  bool recovery_pin_high = false;

 private:
  struct Region {
    Chip* chip;
    std::uint32_t base;
  };
  static constexpr std::uint32_t kTrampoline = kFlashBase + kFlashSize - 0x10;
  static constexpr std::uint64_t kSlice = 64;
  static constexpr std::uint64_t kNever = ~0ull;

  std::string go(std::uint32_t pc, bool until_trampoline);
  void map_region(std::uint32_t base, std::uint32_t size);
  void model_registers();
  std::uint32_t observe(std::uint32_t address);
  void store(std::uint32_t address, std::uint32_t value);
  bool clocked(std::uint32_t address) const;
  void unmodelled(const char* what, std::uint64_t address);
  void fail(const std::string& what);
  bool check(std::uint32_t word, const char* what, std::uint32_t address);
  std::uint32_t otg_read(std::uint32_t address, unsigned size);
  void otg_write(std::uint32_t address, unsigned size, std::uint32_t value);

  // Hardware between instructions.
  void run_hardware_until(std::uint64_t cycle);
  std::uint64_t next_hardware_event() const;
  std::uint32_t tim2_count() const;
  void tim1_start(std::uint64_t at);
  void tim1_update(std::uint64_t at);
  void dma_request(std::uint64_t at);
  void dma_enable(std::uint32_t cr);
  void apply_bsrr(std::uint32_t base, std::uint32_t value, std::uint64_t at, bool by_dma);
  void pend(int irq);
  /// The exception (15: SysTick, 16 + n: IRQ n) to take now, or -1.
  int deliverable_exception();
  bool take_exception(int exception);
  std::uint32_t exception_priority(int exception) const;
  void systick_store(std::uint32_t address, std::uint32_t value);
  void iwdg_store(std::uint32_t offset, std::uint32_t value);
  /// A system reset: AIRCR's SYSRESETREQ, or the watchdog's (`by_watchdog`).
  void system_reset(bool by_watchdog = false);
  static std::uint32_t flash_sector_base(int sector);
  void flash_control(std::uint32_t value);
  static void flash_store(uc_engine*, uc_mem_type, std::uint64_t address, int size,
                          std::int64_t value, void* user);
  void nvic_store(std::uint32_t offset, std::uint32_t value);
  bool nvic_observe(std::uint32_t offset, std::uint32_t* value) const;

  static std::uint64_t mmio_read(uc_engine*, std::uint64_t offset, unsigned size, void* user);
  static void mmio_write(uc_engine*, std::uint64_t offset, unsigned size, std::uint64_t value,
                         void* user);
  static bool unmapped(uc_engine*, uc_mem_type type, std::uint64_t address, int, std::int64_t,
                       void* user);
  static void on_code(uc_engine* uc, std::uint64_t address, std::uint32_t, void* user);

  uc_engine* uc_ = nullptr;
  std::map<std::uint32_t, std::uint32_t> regs_;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> writes_;
  std::vector<std::pair<std::uint32_t, std::string>> stops_;
  std::uint32_t skip_stop_ = 0;
  bool stopped_ = false;
  std::vector<std::unique_ptr<Region>> regions_;
  std::string stopped_at_ = "no stop";
  std::string error_;

  std::uint64_t cycles_ = 0;
  // TIM2: counting since tim2_start_ from tim2_count0_ while CEN.
  std::uint64_t tim2_start_ = 0;
  std::uint32_t tim2_count0_ = 0;
  // TIM1: the cycle of its next update while CEN.
  std::uint64_t tim1_next_update_ = kNever;
  // DMA2 stream 5: words moved since EN, NDTR at EN.
  std::uint32_t dma_index_ = 0;
  std::uint32_t dma_total_ = 0;
  bool strobe_level_ = false;
  // SysTick: the cycle its counter next reaches 0 while enabled; COUNTFLAG.
  std::uint64_t systick_zero_ = kNever;
  bool systick_pending_ = false;
  bool sleeping_ = false;
  bool reset_requested_ = false;
  int system_resets_ = 0;
  // IWDG (RM0090 21.3): the cycle its counter reaches 0 while started; PR and
  // RLR writable after the 0x5555 key; the resets it made.
  std::uint64_t iwdg_zero_ = kNever;
  bool iwdg_unlocked_ = false;
  bool iwdg_expired_ = false;
  std::vector<std::uint64_t> watchdog_resets_;
  OtgFs otg_;
  // NVIC (96 device interrupts).
  std::uint32_t nvic_enabled_[3] = {0, 0, 0};
  std::uint32_t nvic_pending_[3] = {0, 0, 0};
  // Flash option bytes: OPTKEYR sequence, BSY reads left.
  int optkey_step_ = 0;
  int flash_key_step_ = 0;
  std::vector<int> flash_erases_;
  int flash_programs_ = 0;
  int otp_programs_ = 0;
  int flash_busy_reads_ = 0;
  int option_programs_ = 0;
  std::vector<PinWrite> gpioc_writes_;
};

}  // namespace flutterscan::firmware::emu
