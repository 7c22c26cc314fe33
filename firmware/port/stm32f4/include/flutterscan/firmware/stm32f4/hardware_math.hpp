#pragma once
// The pure arithmetic of the stm32f4 port: clock tree, flash wait states,
// timer prescalers, PWM compare values, watchdog reload, reset-cause decoding
// and the DMA request mapping. Host-compilable and constexpr, so host unit
// tests check every number the chip is programmed with (firmware/test/
// stm32f4_hardware_test.cpp). Facts from RM0090 (STM32F405/407).

#include <cstdint>

#include "flutterscan/firmware/port.hpp"

namespace flutterscan::firmware::stm32f4 {

// ---------------------------------------------------------------------------
// Clock tree (RM0090 6.3.2 RCC_PLLCFGR, 6.2 clocks)

/// \brief PLL factors: f_vco = f_in / m * n, SYSCLK = f_vco / p, USB/SDIO = f_vco / q.
struct PllConfig {
  std::uint32_t input_hz = 8'000'000;  ///< HSE crystal (or HSI 16 MHz on fallback)
  std::uint32_t m = 8;                 ///< 2..63, f_in / m in 1..2 MHz
  std::uint32_t n = 336;               ///< 50..432, f_vco in 100..432 MHz
  std::uint32_t p = 2;                 ///< 2, 4, 6 or 8; SYSCLK at most 168 MHz
  std::uint32_t q = 7;                 ///< 2..15; 48 MHz for USB OTG FS
};

/// \brief Bus prescalers: AHB /1, APB1 /4 (at most 42 MHz), APB2 /2 (at most 84 MHz).
struct BusPrescalers {
  std::uint32_t ahb = 1;
  std::uint32_t apb1 = 4;
  std::uint32_t apb2 = 2;
};

/// \brief The frequencies the port programs its peripherals with.
struct ClockTree {
  std::uint32_t sysclk_hz = 0;
  std::uint32_t hclk_hz = 0;
  std::uint32_t pclk1_hz = 0;
  std::uint32_t pclk2_hz = 0;
  std::uint32_t usb_hz = 0;       ///< PLL48CK (0 without PLL)
  std::uint32_t tim_apb1_hz = 0;  ///< TIM2..5: pclk1, doubled when APB1 is divided (RM0090 6.2)
  std::uint32_t tim_apb2_hz = 0;  ///< TIM1/8: pclk2, doubled when APB2 is divided
};

/// The product's PLL: HSE 8 MHz / 8 * 336 = 336 MHz VCO; / 2 = 168 MHz; / 7 = 48 MHz.
inline constexpr PllConfig kPllFromHse{};
/// Fallback if the crystal never starts: HSI 16 MHz / 16 * 336, same outputs
/// (USB then runs off the 1 %-accurate HSI: unreliable, timing still right to 1 %).
inline constexpr PllConfig kPllFromHsi{16'000'000, 16, 336, 2, 7};
inline constexpr std::uint32_t kHsiHz = 16'000'000;
inline constexpr std::uint32_t kMaxSysclkHz = 168'000'000;

/// \brief True if `pll` is within RM0090's ranges and SYSCLK at most 168 MHz.
constexpr bool pll_valid(const PllConfig& pll) {
  if (pll.m < 2 || pll.m > 63 || pll.n < 50 || pll.n > 432 || pll.q < 2 || pll.q > 15) return false;
  if (pll.p != 2 && pll.p != 4 && pll.p != 6 && pll.p != 8) return false;
  const std::uint64_t vco_in = pll.input_hz / pll.m;
  if (pll.input_hz % pll.m != 0 || vco_in < 1'000'000 || vco_in > 2'000'000) return false;
  const std::uint64_t vco = vco_in * pll.n;
  if (vco < 100'000'000 || vco > 432'000'000) return false;
  return vco / pll.p <= kMaxSysclkHz;
}

/// \brief RCC_PLLCFGR value (source HSE if `from_hse`); fields per RM0090 6.3.2.
constexpr std::uint32_t pllcfgr_value(const PllConfig& pll, bool from_hse) {
  return (pll.m << 0) | (pll.n << 6) | (((pll.p / 2) - 1) << 16) | (from_hse ? (1u << 22) : 0u) |
         (pll.q << 24);
}

/// \brief Timer kernel clock of a timer on an APB bus: x1 if the APB prescaler is 1, else x2.
constexpr std::uint32_t timer_clock(std::uint32_t pclk_hz, std::uint32_t apb_prescaler) {
  return apb_prescaler == 1 ? pclk_hz : 2 * pclk_hz;
}

/// \brief The clock tree for SYSCLK `sysclk_hz` (and PLL48CK `usb_hz`) under `buses`.
constexpr ClockTree clock_tree(std::uint32_t sysclk_hz, std::uint32_t usb_hz,
                               const BusPrescalers& buses) {
  ClockTree t;
  t.sysclk_hz = sysclk_hz;
  t.hclk_hz = sysclk_hz / buses.ahb;
  t.pclk1_hz = t.hclk_hz / buses.apb1;
  t.pclk2_hz = t.hclk_hz / buses.apb2;
  t.usb_hz = usb_hz;
  t.tim_apb1_hz = timer_clock(t.pclk1_hz, buses.apb1);
  t.tim_apb2_hz = timer_clock(t.pclk2_hz, buses.apb2);
  return t;
}

/// \brief The clock tree `pll` gives under `buses`.
constexpr ClockTree clock_tree(const PllConfig& pll, const BusPrescalers& buses = {}) {
  const std::uint32_t vco = pll.input_hz / pll.m * pll.n;
  return clock_tree(vco / pll.p, vco / pll.q, buses);
}

/// \brief RCC_CFGR HPRE/PPRE1/PPRE2 field values (RM0090 6.3.3): HPRE 0xxx = /1,
/// 1000 = /2 ... ; PPRE 0xx = /1, 100 = /2, 101 = /4, 110 = /8, 111 = /16.
constexpr std::uint32_t cfgr_prescaler_bits(const BusPrescalers& buses) {
  auto ppre = [](std::uint32_t div) -> std::uint32_t {
    switch (div) {
      case 2: return 0b100;
      case 4: return 0b101;
      case 8: return 0b110;
      case 16: return 0b111;
      default: return 0b000;
    }
  };
  auto hpre = [](std::uint32_t div) -> std::uint32_t {
    switch (div) {
      case 2: return 0b1000;
      case 4: return 0b1001;
      case 8: return 0b1010;
      case 16: return 0b1011;
      default: return 0b0000;  // /64../512 unused
    }
  };
  return (hpre(buses.ahb) << 4) | (ppre(buses.apb1) << 10) | (ppre(buses.apb2) << 13);
}

/// \brief Flash wait states for HCLK at 2.7..3.6 V (RM0090 table 10: one per 30 MHz).
constexpr std::uint32_t flash_wait_states(std::uint32_t hclk_hz) {
  return hclk_hz == 0 ? 0 : (hclk_hz - 1) / 30'000'000;
}

// ---------------------------------------------------------------------------
// Timers

/// \brief Prescaler and auto-reload of a 16-bit timer: period = (psc + 1) * (arr + 1) ticks.
struct TimerPeriod {
  std::uint32_t psc = 0;
  std::uint32_t arr = 0;
};

/// \brief The slot timer's setting for slots of `slot_us` at a timer clock of
/// `timer_hz` (a whole number of MHz): the smallest prescaler dividing the
/// ticks per microsecond whose period fits 16 bits, so every slot is exact.
/// `ok` false if none does (slot_us 0, or a clock that is not whole MHz).
struct SlotTimerSetting {
  bool ok = false;
  TimerPeriod period;
};
constexpr SlotTimerSetting slot_timer_setting(std::uint32_t slot_us, std::uint32_t timer_hz) {
  SlotTimerSetting s;
  if (slot_us == 0 || timer_hz == 0 || timer_hz % 1'000'000 != 0) return s;
  const std::uint32_t ticks_per_us = timer_hz / 1'000'000;
  const std::uint64_t ticks = static_cast<std::uint64_t>(slot_us) * ticks_per_us;
  for (std::uint32_t div = 1; div <= ticks_per_us; ++div) {
    if (ticks_per_us % div != 0) continue;
    const std::uint64_t count = ticks / div;
    if (count >= 2 && count <= 65'536) {
      s.ok = true;
      s.period = {div - 1, static_cast<std::uint32_t>(count - 1)};
      return s;
    }
  }
  return s;
}

/// \brief Nanoseconds one period of a slot timer setting lasts at `timer_hz`.
constexpr std::uint64_t slot_timer_period_ns(const TimerPeriod& p, std::uint32_t timer_hz) {
  return (static_cast<std::uint64_t>(p.psc) + 1) * (static_cast<std::uint64_t>(p.arr) + 1) *
         1'000'000'000ull / timer_hz;
}

/// \brief Prescaler that makes a timer on `timer_hz` count microseconds.
constexpr std::uint32_t microsecond_prescaler(std::uint32_t timer_hz) {
  return timer_hz / 1'000'000 - 1;
}

/// PWM frequency of the brightness outputs (above hearing, easy to filter).
inline constexpr std::uint32_t kBrightnessPwmHz = 20'000;

/// \brief Auto-reload for kBrightnessPwmHz at `timer_hz` (prescaler 1).
constexpr std::uint32_t brightness_pwm_arr(std::uint32_t timer_hz) {
  return timer_hz / kBrightnessPwmHz - 1;
}

/// \brief Compare value for `permille` (clamped to 1000) of a PWM period of arr + 1
/// ticks in PWM mode 1 (output high while CNT < CCR): 0 = off, 1000 = always on.
constexpr std::uint32_t brightness_compare(std::uint16_t permille, std::uint32_t arr) {
  const std::uint32_t p = permille > 1000 ? 1000u : permille;
  const std::uint64_t period = static_cast<std::uint64_t>(arr) + 1;
  return static_cast<std::uint32_t>((period * p + 500) / 1000);
}

// ---------------------------------------------------------------------------
// Independent watchdog (RM0090 21.3: t = 4 * 2^PR * (RLR + 1) / f_LSI)

/// \brief IWDG prescaler code (PR, 0..6 for /4../256) and reload (RLR, 0..4095).
struct WatchdogSetting {
  bool ok = false;
  std::uint32_t pr = 0;
  std::uint32_t rlr = 0;
};

/// \brief The setting closest to (not below) `timeout_ms` at the nominal LSI
/// `lsi_hz` (32 kHz; the real LSI is 17..47 kHz, so the timeout varies about x2).
constexpr WatchdogSetting watchdog_setting(std::uint32_t timeout_ms, std::uint32_t lsi_hz = 32'000) {
  WatchdogSetting w;
  for (std::uint32_t pr = 0; pr <= 6; ++pr) {
    const std::uint64_t divider = 4ull << pr;
    const std::uint64_t ticks =
        (static_cast<std::uint64_t>(timeout_ms) * lsi_hz + divider * 1000 - 1) / (divider * 1000);
    if (ticks >= 1 && ticks <= 4096) {
      w.ok = true;
      w.pr = pr;
      w.rlr = static_cast<std::uint32_t>(ticks - 1);
      return w;
    }
  }
  return w;
}

/// \brief Milliseconds the watchdog setting lasts at `lsi_hz`.
constexpr std::uint32_t watchdog_timeout_ms(const WatchdogSetting& w, std::uint32_t lsi_hz = 32'000) {
  return static_cast<std::uint32_t>((4ull << w.pr) * (w.rlr + 1ull) * 1000 / lsi_hz);
}

// ---------------------------------------------------------------------------
// Reset cause (RCC_CSR flags, RM0090 7.3.21)

/// \brief Why the chip started, from RCC_CSR: either watchdog -> kWatchdog;
/// software reset (SYSRESETREQ, e.g. after a firmware update) -> kSoftware;
/// power-on, brown-out, pin and low-power resets -> kPowerOn.
constexpr ResetCause reset_cause_from_csr(std::uint32_t csr) {
  constexpr std::uint32_t kIwdg = 1u << 29;
  constexpr std::uint32_t kWwdg = 1u << 30;
  constexpr std::uint32_t kSoftwareReset = 1u << 28;
  if (csr & (kIwdg | kWwdg)) return ResetCause::kWatchdog;
  if (csr & kSoftwareReset) return ResetCause::kSoftware;
  return ResetCause::kPowerOn;
}

// ---------------------------------------------------------------------------
// DMA request mapping (RM0090 table 43, DMA2 request mapping)

/// \brief A DMA stream and the channel (CHSEL) that connects one peripheral request to it.
struct DmaRoute {
  int controller = 0;  ///< 1 or 2
  int stream = 0;      ///< 0..7
  int channel = 0;     ///< 0..7 (CHSEL)
};

/// TIM1_UP: DMA2 stream 5 channel 6 (the only route for TIM1's update request).
/// Only DMA2 has a path to the AHB1 GPIO ports (RM0090 2.1 bus matrix), and only
/// TIM1 and TIM8 of the timers have DMA2 requests: this is the slot timer's route.
inline constexpr DmaRoute kTim1UpRoute{2, 5, 6};
/// TIM8_UP: DMA2 stream 1 channel 7 (the alternative slot timer; unused).
inline constexpr DmaRoute kTim8UpRoute{2, 1, 7};

}  // namespace flutterscan::firmware::stm32f4
