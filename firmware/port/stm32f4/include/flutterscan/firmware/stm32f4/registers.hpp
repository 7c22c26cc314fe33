#pragma once
// The STM32F405 and Cortex-M4 registers the product image touches, written for
// this project from the reference manuals (no vendor headers):
// RM0090 rev 19 (STM32F405/407 reference manual) for the peripherals and
// PM0214 (Cortex-M4 programming manual) for SCB, SysTick and NVIC.
// Addresses and bit positions are constexpr, so host tests can check the
// arithmetic; `at()` itself only makes sense on the chip.

#include <cstdint>

namespace flutterscan::firmware::stm32f4::reg {

/// \brief The 32-bit memory-mapped register at `address` (on the chip only).
inline volatile std::uint32_t& at(std::uintptr_t address) {
  return *reinterpret_cast<volatile std::uint32_t*>(address);
}

/// \brief Reads the register at `address` once (also: waits for a bus write to complete).
inline std::uint32_t read(std::uintptr_t address) {
  return at(address);
}

/// \brief Sets `bits` in the register at `address` (read-modify-write).
inline void set_bits(std::uintptr_t address, std::uint32_t bits) {
  volatile std::uint32_t& r = at(address);
  r = r | bits;
}

/// \brief Clears `bits` in the register at `address` (read-modify-write).
inline void clear_bits(std::uintptr_t address, std::uint32_t bits) {
  volatile std::uint32_t& r = at(address);
  r = r & ~bits;
}

/// \brief Replaces the bits under `mask` with `value` (already shifted) at `address`.
inline void modify(std::uintptr_t address, std::uint32_t mask, std::uint32_t value) {
  volatile std::uint32_t& r = at(address);
  r = (r & ~mask) | (value & mask);
}

// ---------------------------------------------------------------------------
// Cortex-M4 core (PM0214)

// PM0214 4.4: system control block.
namespace scb {
inline constexpr std::uintptr_t kVtor = 0xE000ED08;   ///< vector table offset
inline constexpr std::uintptr_t kAircr = 0xE000ED0C;  ///< application interrupt and reset control
inline constexpr std::uintptr_t kShpr3 =
    0xE000ED20;  ///< priorities of PendSV (23:16), SysTick (31:24)
inline constexpr std::uintptr_t kCpacr = 0xE000ED88;  ///< coprocessor access control (4.6.1)
/// AIRCR write key (31:16) with SYSRESETREQ (bit 2): a system reset.
inline constexpr std::uint32_t kAircrSystemReset = (0x05FAu << 16) | (1u << 2);
/// CP10 and CP11 (the FPU) full access: bits 20..23.
inline constexpr std::uint32_t kCpacrFpuFullAccess = 0xFu << 20;
}  // namespace scb

// PM0214 4.5: SysTick (24-bit down counter).
namespace systick {
inline constexpr std::uintptr_t kCtrl = 0xE000E010;
inline constexpr std::uintptr_t kLoad = 0xE000E014;
inline constexpr std::uintptr_t kVal = 0xE000E018;
inline constexpr std::uint32_t kCtrlEnable = 1u << 0;
inline constexpr std::uint32_t kCtrlTickInt = 1u << 1;
inline constexpr std::uint32_t kCtrlClkSource = 1u << 2;  ///< 1: processor clock (HCLK)
}  // namespace systick

// PM0214 4.3: NVIC. Interrupt n: enable bit n % 32 of ISER[n / 32]; priority byte n of IPR.
namespace nvic {
inline constexpr std::uintptr_t kIser0 = 0xE000E100;
inline constexpr std::uintptr_t kIcer0 = 0xE000E180;
inline constexpr std::uintptr_t kIcpr0 = 0xE000E280;
inline constexpr std::uintptr_t kIpr0 = 0xE000E400;
/// \brief Address of the set-enable (or clear-enable, from kIcer0) word holding interrupt `irq`.
constexpr std::uintptr_t word_for(std::uintptr_t base, int irq) {
  return base + 4u * static_cast<std::uintptr_t>(irq / 32);
}
/// \brief The bit of interrupt `irq` in its ISER/ICER/ICPR word.
constexpr std::uint32_t bit_for(int irq) {
  return 1u << (irq % 32);
}
/// The F405 implements the top 4 priority bits (RM0090 12.1.1: 16 levels).
inline constexpr int kPriorityBits = 4;
}  // namespace nvic

// RM0090 table 61: the interrupt positions (IRQn) the image uses.
namespace irq {
inline constexpr int kTim2 = 28;
inline constexpr int kDma2Stream5 = 68;
inline constexpr int kOtgFs = 67;  ///< OTG_FS global interrupt
/// Maskable interrupts of the STM32F405/407 (positions 0..81).
inline constexpr int kCount = 82;
}  // namespace irq

// DBGMCU (RM0090 38.16.4): freeze the watchdog while the core is halted by a debugger.
namespace dbgmcu {
inline constexpr std::uintptr_t kApb1Fz = 0xE0042008;
inline constexpr std::uint32_t kApb1FzIwdgStop = 1u << 12;
}  // namespace dbgmcu

// ---------------------------------------------------------------------------
// RM0090 2.3 (memory map) and the peripherals

// RM0090 7.3: reset and clock control.
namespace rcc {
inline constexpr std::uintptr_t kBase = 0x40023800;
inline constexpr std::uintptr_t kCr = kBase + 0x00;
inline constexpr std::uintptr_t kPllCfgr = kBase + 0x04;
inline constexpr std::uintptr_t kCfgr = kBase + 0x08;
inline constexpr std::uintptr_t kAhb1Enr = kBase + 0x30;
inline constexpr std::uintptr_t kAhb2Enr = kBase + 0x34;
inline constexpr std::uintptr_t kApb1Enr = kBase + 0x40;
inline constexpr std::uintptr_t kApb2Enr = kBase + 0x44;
inline constexpr std::uintptr_t kCsr = kBase + 0x74;

// RCC_CR
inline constexpr std::uint32_t kCrHsiOn = 1u << 0;
inline constexpr std::uint32_t kCrHsiRdy = 1u << 1;
inline constexpr std::uint32_t kCrHseOn = 1u << 16;
inline constexpr std::uint32_t kCrHseRdy = 1u << 17;
inline constexpr std::uint32_t kCrHseByp = 1u << 18;
inline constexpr std::uint32_t kCrCssOn = 1u << 19;
inline constexpr std::uint32_t kCrPllOn = 1u << 24;
inline constexpr std::uint32_t kCrPllRdy = 1u << 25;

// RCC_PLLCFGR: PLLM 5:0, PLLN 14:6, PLLP 17:16 ((P / 2) - 1), PLLSRC 22, PLLQ 27:24.
inline constexpr int kPllCfgrMShift = 0;
inline constexpr int kPllCfgrNShift = 6;
inline constexpr int kPllCfgrPShift = 16;
inline constexpr std::uint32_t kPllCfgrSrcHse = 1u << 22;
inline constexpr int kPllCfgrQShift = 24;

// RCC_CFGR: SW 1:0, SWS 3:2, HPRE 7:4, PPRE1 12:10, PPRE2 15:13.
inline constexpr std::uint32_t kCfgrSwMask = 0b11u;
inline constexpr std::uint32_t kCfgrSwHsi = 0b00u;
inline constexpr std::uint32_t kCfgrSwPll = 0b10u;
inline constexpr std::uint32_t kCfgrSwsMask = 0b11u << 2;
inline constexpr std::uint32_t kCfgrSwsPll = 0b10u << 2;
inline constexpr int kCfgrHpreShift = 4;
inline constexpr int kCfgrPpre1Shift = 10;
inline constexpr int kCfgrPpre2Shift = 13;
inline constexpr std::uint32_t kCfgrPrescalerMask = (0xFu << 4) | (0b111u << 10) | (0b111u << 13);

// RCC_AHB1ENR
inline constexpr std::uint32_t kAhb1EnrGpioA = 1u << 0;
inline constexpr std::uint32_t kAhb1EnrGpioB = 1u << 1;
inline constexpr std::uint32_t kAhb1EnrGpioC = 1u << 2;
inline constexpr std::uint32_t kAhb1EnrDma2 = 1u << 22;
// RCC_AHB2ENR
inline constexpr std::uint32_t kAhb2EnrOtgFs = 1u << 7;
// RCC_APB1ENR
inline constexpr std::uint32_t kApb1EnrTim2 = 1u << 0;
inline constexpr std::uint32_t kApb1EnrTim3 = 1u << 1;
inline constexpr std::uint32_t kApb1EnrTim5 = 1u << 3;
inline constexpr std::uint32_t kApb1EnrPwr = 1u << 28;
// RCC_APB2ENR
inline constexpr std::uint32_t kApb2EnrTim1 = 1u << 0;

// RCC_CSR: LSI and the reset flags (cleared together by RMVF).
inline constexpr std::uint32_t kCsrLsiOn = 1u << 0;
inline constexpr std::uint32_t kCsrLsiRdy = 1u << 1;
inline constexpr std::uint32_t kCsrRmvf = 1u << 24;
inline constexpr std::uint32_t kCsrBorRstf = 1u << 25;
inline constexpr std::uint32_t kCsrPinRstf = 1u << 26;
inline constexpr std::uint32_t kCsrPorRstf = 1u << 27;
inline constexpr std::uint32_t kCsrSftRstf = 1u << 28;
inline constexpr std::uint32_t kCsrIwdgRstf = 1u << 29;
inline constexpr std::uint32_t kCsrWwdgRstf = 1u << 30;
inline constexpr std::uint32_t kCsrLpwrRstf = 1u << 31;
/// Every reset flag, BORRSTF..LPWRRSTF (bits 31:25).
inline constexpr std::uint32_t kCsrResetFlags = 0xFE000000;
}  // namespace rcc

// RM0090 5.4: power control (VOS: regulator scale 1 for HCLK above 144 MHz).
namespace pwr {
inline constexpr std::uintptr_t kCr = 0x40007000;
inline constexpr std::uint32_t kCrVos = 1u << 14;
}  // namespace pwr

// RM0090 3.9: flash interface.
namespace flash {
inline constexpr std::uintptr_t kBase = 0x40023C00;
inline constexpr std::uintptr_t kAcr = kBase + 0x00;
inline constexpr std::uintptr_t kKeyr = kBase + 0x04;
inline constexpr std::uintptr_t kSr = kBase + 0x0C;
inline constexpr std::uintptr_t kCr = kBase + 0x10;
inline constexpr std::uintptr_t kOptKeyr = kBase + 0x08;
inline constexpr std::uintptr_t kOptcr = kBase + 0x14;
inline constexpr std::uint32_t kKey1 = 0x45670123;
inline constexpr std::uint32_t kKey2 = 0xCDEF89AB;
// FLASH_OPTKEYR unlock sequence (RM0090 3.6.2), FLASH_OPTCR (3.9.7): OPTLOCK 0,
// OPTSTRT 1, BOR_LEV 3:2, USER 7:5, RDP 15:8, nWRP 27:16 (bit 16 + n: sector n,
// 0 = write-protected). Reset value with the factory option bytes: 0x0FFFAAED.
inline constexpr std::uint32_t kOptKey1 = 0x08192A3B;
inline constexpr std::uint32_t kOptKey2 = 0x4C5D6E7F;
inline constexpr std::uint32_t kOptcrOptLock = 1u << 0;
inline constexpr std::uint32_t kOptcrOptStrt = 1u << 1;
inline constexpr int kOptcrNwrpShift = 16;
constexpr std::uint32_t optcr_nwrp(int sector) {
  return 1u << (kOptcrNwrpShift + sector);
}
// FLASH_ACR: LATENCY 2:0, PRFTEN 8, ICEN 9, DCEN 10, ICRST 11, DCRST 12.
inline constexpr std::uint32_t kAcrLatencyMask = 0b111u;
inline constexpr std::uint32_t kAcrPrftEn = 1u << 8;
inline constexpr std::uint32_t kAcrIcEn = 1u << 9;
inline constexpr std::uint32_t kAcrDcEn = 1u << 10;
inline constexpr std::uint32_t kAcrIcRst = 1u << 11;
inline constexpr std::uint32_t kAcrDcRst = 1u << 12;
// FLASH_SR
inline constexpr std::uint32_t kSrEop = 1u << 0;
inline constexpr std::uint32_t kSrOperr = 1u << 1;
inline constexpr std::uint32_t kSrWrperr = 1u << 4;
inline constexpr std::uint32_t kSrPgaerr = 1u << 5;
inline constexpr std::uint32_t kSrPgperr = 1u << 6;
inline constexpr std::uint32_t kSrPgserr = 1u << 7;
inline constexpr std::uint32_t kSrBsy = 1u << 16;
inline constexpr std::uint32_t kSrErrors = kSrOperr | kSrWrperr | kSrPgaerr | kSrPgperr | kSrPgserr;
// FLASH_CR: PG 0, SER 1, SNB 6:3, PSIZE 9:8 (0b10: x32), STRT 16, LOCK 31.
inline constexpr std::uint32_t kCrPg = 1u << 0;
inline constexpr std::uint32_t kCrSer = 1u << 1;
inline constexpr int kCrSnbShift = 3;
inline constexpr std::uint32_t kCrSnbMask = 0xFu << 3;
inline constexpr std::uint32_t kCrPsizeX32 = 0b10u << 8;
inline constexpr std::uint32_t kCrPsizeMask = 0b11u << 8;
inline constexpr std::uint32_t kCrStrt = 1u << 16;
inline constexpr std::uint32_t kCrLock = 1u << 31;
}  // namespace flash

// RM0090 8.4: GPIO ports A..I at 0x40020000 + 0x400 * port.
namespace gpio {
inline constexpr std::uintptr_t kPortA = 0x40020000;
inline constexpr std::uintptr_t kPortStride = 0x400;
/// \brief Base address of GPIO port `index` (0 = A, 1 = B, 2 = C, ...).
constexpr std::uintptr_t port(int index) {
  return kPortA + kPortStride * static_cast<std::uintptr_t>(index);
}
inline constexpr std::uintptr_t kModer = 0x00;    ///< 2 bits per pin
inline constexpr std::uintptr_t kOtyper = 0x04;   ///< 1 bit per pin: 0 push-pull
inline constexpr std::uintptr_t kOspeedr = 0x08;  ///< 2 bits per pin
inline constexpr std::uintptr_t kPupdr = 0x0C;    ///< 2 bits per pin: 00 none, 01 up, 10 down
inline constexpr std::uintptr_t kIdr = 0x10;
inline constexpr std::uintptr_t kBsrr = 0x18;  ///< bit p sets pin p, bit 16+p resets it
inline constexpr std::uintptr_t kAfrl = 0x20;  ///< 4 bits per pin 0..7
inline constexpr std::uintptr_t kAfrh = 0x24;  ///< 4 bits per pin 8..15
inline constexpr std::uint32_t kModeInput = 0b00;
inline constexpr std::uint32_t kModeOutput = 0b01;
inline constexpr std::uint32_t kModeAlternate = 0b10;
inline constexpr std::uint32_t kSpeedHigh = 0b10;
inline constexpr std::uint32_t kPullDown = 0b10;
}  // namespace gpio

// RM0090 10: DMA controllers. DMA2 at 0x40026400; stream s registers at 0x10 + 0x18 * s.
namespace dma {
inline constexpr std::uintptr_t kDma2 = 0x40026400;
inline constexpr std::uintptr_t kLisr = 0x00;   ///< streams 0..3 flags
inline constexpr std::uintptr_t kHisr = 0x04;   ///< streams 4..7 flags
inline constexpr std::uintptr_t kLifcr = 0x08;  ///< streams 0..3 flag clear
inline constexpr std::uintptr_t kHifcr = 0x0C;  ///< streams 4..7 flag clear
/// \brief Base address of stream `stream` of the controller at `dma`.
constexpr std::uintptr_t stream(std::uintptr_t dma, int s) {
  return dma + 0x10 + 0x18 * static_cast<std::uintptr_t>(s);
}
inline constexpr std::uintptr_t kSxCr = 0x00;
inline constexpr std::uintptr_t kSxNdtr = 0x04;
inline constexpr std::uintptr_t kSxPar = 0x08;
inline constexpr std::uintptr_t kSxM0ar = 0x0C;
inline constexpr std::uintptr_t kSxFcr = 0x14;
/// \brief Interrupt status / flag clear register (offset) holding stream `s`'s flags.
constexpr std::uintptr_t status_register(int s) {
  return s < 4 ? kLisr : kHisr;
}
constexpr std::uintptr_t clear_register(int s) {
  return s < 4 ? kLifcr : kHifcr;
}
/// \brief Position of stream `s`'s FEIF bit in its status word (RM0090 10.5.1/10.5.2):
/// streams 0/4 at 0, 1/5 at 6, 2/6 at 16, 3/7 at 22.
constexpr int flag_shift(int s) {
  constexpr int kShifts[4] = {0, 6, 16, 22};
  return kShifts[s % 4];
}
// The five flags of a stream, relative to flag_shift().
inline constexpr std::uint32_t kFlagFe = 1u << 0;
inline constexpr std::uint32_t kFlagDme = 1u << 2;
inline constexpr std::uint32_t kFlagTe = 1u << 3;
inline constexpr std::uint32_t kFlagHt = 1u << 4;
inline constexpr std::uint32_t kFlagTc = 1u << 5;
inline constexpr std::uint32_t kFlagAll = kFlagFe | kFlagDme | kFlagTe | kFlagHt | kFlagTc;
// DMA_SxCR
inline constexpr std::uint32_t kCrEn = 1u << 0;
inline constexpr std::uint32_t kCrTeie = 1u << 2;
inline constexpr std::uint32_t kCrTcie = 1u << 4;
inline constexpr std::uint32_t kCrDirMemToPeriph = 0b01u << 6;
inline constexpr std::uint32_t kCrMinc = 1u << 10;
inline constexpr std::uint32_t kCrPsize32 = 0b10u << 11;
inline constexpr std::uint32_t kCrMsize32 = 0b10u << 13;
inline constexpr std::uint32_t kCrPlVeryHigh = 0b11u << 16;
inline constexpr int kCrChselShift = 25;
}  // namespace dma

// RM0090 17 (TIM1/TIM8) and 18 (TIM2..TIM5): the register offsets they share.
namespace tim {
inline constexpr std::uintptr_t kTim1 = 0x40010000;  ///< APB2
inline constexpr std::uintptr_t kTim2 = 0x40000000;  ///< APB1, 32-bit
inline constexpr std::uintptr_t kTim3 = 0x40000400;  ///< APB1, 16-bit
inline constexpr std::uintptr_t kTim5 = 0x40000C00;  ///< APB1, 32-bit
inline constexpr std::uintptr_t kCr1 = 0x00;
inline constexpr std::uintptr_t kCr2 = 0x04;
inline constexpr std::uintptr_t kSmcr = 0x08;
inline constexpr std::uintptr_t kDier = 0x0C;
inline constexpr std::uintptr_t kSr = 0x10;
inline constexpr std::uintptr_t kEgr = 0x14;
inline constexpr std::uintptr_t kCcmr1 = 0x18;
inline constexpr std::uintptr_t kCcmr2 = 0x1C;
inline constexpr std::uintptr_t kCcer = 0x20;
inline constexpr std::uintptr_t kCnt = 0x24;
inline constexpr std::uintptr_t kPsc = 0x28;
inline constexpr std::uintptr_t kArr = 0x2C;
inline constexpr std::uintptr_t kCcr1 = 0x34;
inline constexpr std::uintptr_t kCcr2 = 0x38;
inline constexpr std::uintptr_t kCcr3 = 0x3C;
inline constexpr std::uintptr_t kCcr4 = 0x40;
/// \brief Offset of CCRn (channel 1..4).
constexpr std::uintptr_t ccr(int channel) {
  return kCcr1 + 4u * static_cast<std::uintptr_t>(channel - 1);
}
inline constexpr std::uintptr_t kBdtr = 0x44;  ///< TIM1/TIM8 only
// CR1
inline constexpr std::uint32_t kCr1Cen = 1u << 0;
inline constexpr std::uint32_t kCr1Urs = 1u << 2;  ///< only over/underflow makes update IRQ/DMA
inline constexpr std::uint32_t kCr1Arpe = 1u << 7;
// CR2: MMS 6:4 (master mode: what TRGO carries).
inline constexpr int kCr2MmsShift = 4;
inline constexpr std::uint32_t kCr2MmsMask = 0b111u << 4;
inline constexpr std::uint32_t kMmsComparePulse = 0b011;  ///< TRGO pulses when CC1IF is set
inline constexpr std::uint32_t kMmsOc3Ref = 0b110;        ///< TRGO = OC3REF
// SMCR: SMS 2:0, TS 6:4.
inline constexpr std::uint32_t kSmcrSmsMask = 0b111u;
inline constexpr std::uint32_t kSmsEncoderMode3 = 0b011;  ///< count on TI1 and TI2 edges
inline constexpr std::uint32_t kSmsTrigger = 0b110;       ///< the trigger sets CEN
inline constexpr int kSmcrTsShift = 4;
inline constexpr std::uint32_t kSmcrTsMask = 0b111u << 4;
/// TIM1's ITR1 is TIM2's TRGO (RM0090 table 86, TIMx internal trigger connection).
inline constexpr std::uint32_t kTim1TsItr1Tim2 = 0b001;
// DIER
inline constexpr std::uint32_t kDierUie = 1u << 0;
inline constexpr std::uint32_t kDierCc1Ie = 1u << 1;
inline constexpr std::uint32_t kDierCc2Ie = 1u << 2;
inline constexpr std::uint32_t kDierCc3Ie = 1u << 3;
inline constexpr std::uint32_t kDierUde = 1u << 8;
// SR
inline constexpr std::uint32_t kSrUif = 1u << 0;
inline constexpr std::uint32_t kSrCc1If = 1u << 1;
inline constexpr std::uint32_t kSrCc2If = 1u << 2;
inline constexpr std::uint32_t kSrCc3If = 1u << 3;
inline constexpr std::uint32_t kSrCc1Of = 1u << 9;
inline constexpr std::uint32_t kSrCc2Of = 1u << 10;
// EGR
inline constexpr std::uint32_t kEgrUg = 1u << 0;
// CCMRx, one channel's byte (channel 1/3 at bit 0, 2/4 at bit 8).
inline constexpr std::uint32_t kCcsInputOwn = 0b01;    ///< ICx on TIx
inline constexpr std::uint32_t kCcsInputOther = 0b10;  ///< IC1 on TI2, IC2 on TI1
inline constexpr int kIcFilterShift = 4;               ///< ICxF 7:4
inline constexpr std::uint32_t kOcPreload = 1u << 3;   ///< OCxPE
inline constexpr int kOcModeShift = 4;                 ///< OCxM 6:4
inline constexpr std::uint32_t kOcModeActiveOnMatch = 0b001;
inline constexpr std::uint32_t kOcModeInactiveOnMatch = 0b010;
inline constexpr std::uint32_t kOcModeForceInactive = 0b100;
inline constexpr std::uint32_t kOcModePwm1 = 0b110;
/// Input filter fSAMPLING = fCK_INT, N = 8 (ICxF = 0011): 8 equal samples.
inline constexpr std::uint32_t kIcFilterN8 = 0b0011;
// CCER: 4 bits per channel (CCxE, CCxP, -, CCxNP).
constexpr int ccer_shift(int channel) {
  return 4 * (channel - 1);
}
inline constexpr std::uint32_t kCcerE = 1u << 0;
inline constexpr std::uint32_t kCcerP = 1u << 1;
}  // namespace tim

// RM0090 21: independent watchdog (LSI clock, nominally 32 kHz).
namespace iwdg {
inline constexpr std::uintptr_t kKr = 0x40003000;
inline constexpr std::uintptr_t kPr = 0x40003004;
inline constexpr std::uintptr_t kRlr = 0x40003008;
inline constexpr std::uintptr_t kSr = 0x4000300C;
inline constexpr std::uint32_t kKeyReload = 0xAAAA;
inline constexpr std::uint32_t kKeyUnlock = 0x5555;
inline constexpr std::uint32_t kKeyStart = 0xCCCC;
inline constexpr std::uint32_t kSrPvu = 1u << 0;
inline constexpr std::uint32_t kSrRvu = 1u << 1;
}  // namespace iwdg

// RM0090 34: USB on-the-go full-speed (OTG_FS) at 0x50000000, used in device
// mode only. Core global registers 34.16.2, device registers 34.16.4.
namespace otg {
inline constexpr std::uintptr_t kBase = 0x50000000;
// Core global registers.
inline constexpr std::uintptr_t kGahbcfg = kBase + 0x008;
inline constexpr std::uintptr_t kGusbcfg = kBase + 0x00C;
inline constexpr std::uintptr_t kGrstctl = kBase + 0x010;
inline constexpr std::uintptr_t kGintsts = kBase + 0x014;
inline constexpr std::uintptr_t kGintmsk = kBase + 0x018;
inline constexpr std::uintptr_t kGrxstsp = kBase + 0x020;  ///< receive status read and pop
inline constexpr std::uintptr_t kGrxfsiz = kBase + 0x024;  ///< RX FIFO depth (words)
inline constexpr std::uintptr_t kDieptxf0 =
    kBase + 0x028;  ///< EP0 TX FIFO: start 15:0, depth 31:16
inline constexpr std::uintptr_t kGccfg = kBase + 0x038;
/// \brief OTG_FS_DIEPTXFx (x = 1..3): IN endpoint x's TX FIFO start and depth (words).
constexpr std::uintptr_t dieptxf(int ep) {
  return kBase + 0x104 + 4u * static_cast<std::uintptr_t>(ep - 1);
}
// Device registers.
inline constexpr std::uintptr_t kDcfg = kBase + 0x800;
inline constexpr std::uintptr_t kDctl = kBase + 0x804;
inline constexpr std::uintptr_t kDsts = kBase + 0x808;
inline constexpr std::uintptr_t kDiepmsk = kBase + 0x810;
inline constexpr std::uintptr_t kDoepmsk = kBase + 0x814;
inline constexpr std::uintptr_t kDaint = kBase + 0x818;
inline constexpr std::uintptr_t kDaintmsk = kBase + 0x81C;
constexpr std::uintptr_t diepctl(int ep) {
  return kBase + 0x900 + 0x20u * static_cast<std::uintptr_t>(ep);
}
constexpr std::uintptr_t diepint(int ep) {
  return kBase + 0x908 + 0x20u * static_cast<std::uintptr_t>(ep);
}
constexpr std::uintptr_t dieptsiz(int ep) {
  return kBase + 0x910 + 0x20u * static_cast<std::uintptr_t>(ep);
}
constexpr std::uintptr_t dtxfsts(int ep) {
  return kBase + 0x918 + 0x20u * static_cast<std::uintptr_t>(ep);
}
constexpr std::uintptr_t doepctl(int ep) {
  return kBase + 0xB00 + 0x20u * static_cast<std::uintptr_t>(ep);
}
constexpr std::uintptr_t doepint(int ep) {
  return kBase + 0xB08 + 0x20u * static_cast<std::uintptr_t>(ep);
}
constexpr std::uintptr_t doeptsiz(int ep) {
  return kBase + 0xB10 + 0x20u * static_cast<std::uintptr_t>(ep);
}
inline constexpr std::uintptr_t kPcgcctl = kBase + 0xE00;
/// \brief The data FIFO of endpoint `ep`: IN pushes here; reads from any of them pop the RX FIFO.
constexpr std::uintptr_t fifo(int ep) {
  return kBase + 0x1000 + 0x1000u * static_cast<std::uintptr_t>(ep);
}
/// Endpoints of the OTG_FS core (0..3 each way) and its FIFO RAM (1.25 KiB).
inline constexpr int kEndpoints = 4;
inline constexpr std::uint32_t kFifoRamWords = 320;

// GAHBCFG
inline constexpr std::uint32_t kGahbcfgGintmsk = 1u << 0;  ///< global interrupt enable
// GUSBCFG: PHYSEL 6 (full-speed transceiver), TRDT 13:10, FDMOD 30.
inline constexpr std::uint32_t kGusbcfgPhysel = 1u << 6;
inline constexpr int kGusbcfgTrdtShift = 10;
inline constexpr std::uint32_t kGusbcfgTrdtMask = 0xFu << 10;
inline constexpr std::uint32_t kGusbcfgFhmod = 1u << 29;
inline constexpr std::uint32_t kGusbcfgFdmod = 1u << 30;
// GRSTCTL: CSRST 0, RXFFLSH 4, TXFFLSH 5, TXFNUM 10:6 (0x10: all), AHBIDL 31.
inline constexpr std::uint32_t kGrstctlCsrst = 1u << 0;
inline constexpr std::uint32_t kGrstctlRxfflsh = 1u << 4;
inline constexpr std::uint32_t kGrstctlTxfflsh = 1u << 5;
inline constexpr int kGrstctlTxfnumShift = 6;
inline constexpr std::uint32_t kGrstctlTxfnumAll = 0x10;
inline constexpr std::uint32_t kGrstctlAhbidl = 1u << 31;
// GINTSTS / GINTMSK
inline constexpr std::uint32_t kGintRxflvl = 1u << 4;
inline constexpr std::uint32_t kGintUsbsusp = 1u << 11;
inline constexpr std::uint32_t kGintUsbrst = 1u << 12;
inline constexpr std::uint32_t kGintEnumdne = 1u << 13;
inline constexpr std::uint32_t kGintIepint = 1u << 18;
inline constexpr std::uint32_t kGintOepint = 1u << 19;
inline constexpr std::uint32_t kGintWkupint = 1u << 31;
// GRXSTSP: EPNUM 3:0, BCNT 14:4, DPID 16:15, PKTSTS 20:17.
inline constexpr std::uint32_t kRxstsEpnumMask = 0xFu;
inline constexpr int kRxstsBcntShift = 4;
inline constexpr std::uint32_t kRxstsBcntMask = 0x7FFu << 4;
inline constexpr int kRxstsPktstsShift = 17;
inline constexpr std::uint32_t kRxstsPktstsMask = 0xFu << 17;
inline constexpr std::uint32_t kPktstsOutData = 2;      ///< OUT data packet received
inline constexpr std::uint32_t kPktstsOutComplete = 3;  ///< OUT transfer completed
inline constexpr std::uint32_t kPktstsSetupDone = 4;    ///< SETUP transaction completed
inline constexpr std::uint32_t kPktstsSetupData = 6;    ///< SETUP data packet received
// GCCFG: PWRDWN 16 (transceiver on), VBUSASEN 18, VBUSBSEN 19, NOVBUSSENS 21.
inline constexpr std::uint32_t kGccfgPwrdwn = 1u << 16;
inline constexpr std::uint32_t kGccfgVbusasen = 1u << 18;
inline constexpr std::uint32_t kGccfgVbusbsen = 1u << 19;
inline constexpr std::uint32_t kGccfgNovbussens = 1u << 21;
// DCFG: DSPD 1:0 (0b11: full speed), DAD 10:4.
inline constexpr std::uint32_t kDcfgDspdFullSpeed = 0b11u;
inline constexpr int kDcfgDadShift = 4;
inline constexpr std::uint32_t kDcfgDadMask = 0x7Fu << 4;
// DCTL: SDIS 1 (soft disconnect), CGINAK 8, CGONAK 10.
inline constexpr std::uint32_t kDctlSdis = 1u << 1;
inline constexpr std::uint32_t kDctlCginak = 1u << 8;
inline constexpr std::uint32_t kDctlCgonak = 1u << 10;
// DIEPCTLx / DOEPCTLx: MPSIZ 10:0 (EP0: 1:0, 0b00 = 64 bytes), USBAEP 15,
// EPTYP 19:18, STALL 21, TXFNUM 25:22 (IN), CNAK 26, SNAK 27, SD0PID 28, EPDIS 30, EPENA 31.
inline constexpr std::uint32_t kEpctlMpsizMask = 0x7FFu;
inline constexpr std::uint32_t kEpctlUsbaep = 1u << 15;
inline constexpr int kEpctlEptypShift = 18;
inline constexpr std::uint32_t kEpctlStall = 1u << 21;
inline constexpr int kEpctlTxfnumShift = 22;
inline constexpr std::uint32_t kEpctlCnak = 1u << 26;
inline constexpr std::uint32_t kEpctlSnak = 1u << 27;
inline constexpr std::uint32_t kEpctlSd0pid = 1u << 28;
inline constexpr std::uint32_t kEpctlEpdis = 1u << 30;
inline constexpr std::uint32_t kEpctlEpena = 1u << 31;
// DIEPINTx / DOEPINTx: XFRC 0, EPDISD 1, STUP 3 (OUT), TOC 3 (IN).
inline constexpr std::uint32_t kEpintXfrc = 1u << 0;
inline constexpr std::uint32_t kEpintEpdisd = 1u << 1;
inline constexpr std::uint32_t kEpintStup = 1u << 3;
inline constexpr std::uint32_t kEpintToc = 1u << 3;
// DIEPTSIZx / DOEPTSIZx: XFRSIZ 18:0 (EP0: 6:0), PKTCNT 28:19 (EP0 IN: 20:19,
// EP0 OUT: bit 19), STUPCNT 30:29 (EP0 OUT).
inline constexpr int kTsizPktcntShift = 19;
inline constexpr int kTsizStupcntShift = 29;
}  // namespace otg

// RM0090 39.1: the 96-bit unique device ID (12 bytes, read-only).
inline constexpr std::uintptr_t kUniqueIdAddress = 0x1FFF7A10;

}  // namespace flutterscan::firmware::stm32f4::reg
