// The real bootloader ELF (build-fw-stm32f405) executed instruction by
// instruction in the Unicorn engine (label emu, issue 15 item 4, a first
// step): from the reset vector through Reset_Handler's decision
// (boot_decision.hpp) to either the application's reset handler (VTOR, MSP
// and the jump of start_application) or bootloader_main (DFU mode). The
// peripherals it touches on that path are modelled from RM0090 / PM0214:
// RCC_AHB1ENR, GPIOB MODER/PUPDR/IDR (the recovery pin PB2), SCB VTOR and
// CPACR. Any other access, to a peripheral or a register not modelled, fails
// the test loudly. Not modelled (so not reached): clocks, flash interface,
// OTG_FS, timers, DMA of the application; the emulation stops at the first
// instruction of the application or of bootloader_main.
// Skipped (exit 77 via GTEST_SKIP) without the built ELF and image.

#include <gtest/gtest.h>
#include <unicorn/unicorn.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "flutterscan/common/crc32.hpp"
#include "flutterscan/common/image_header.hpp"
#include "flutterscan/firmware/boot_decision.hpp"

namespace flutterscan::firmware::emu {
namespace {

constexpr std::uint32_t kFlashBase = 0x08000000;
constexpr std::uint32_t kFlashSize = 1024 * 1024;
constexpr std::uint32_t kSramBase = 0x20000000;
constexpr std::uint32_t kSramSize = 128 * 1024;
constexpr std::uint32_t kAppBase = 0x08008000;
// RM0090 2.3 memory map, 7.3 RCC, 8.4 GPIO; PM0214 4.3 SCB.
constexpr std::uint32_t kRccBase = 0x40023800;
constexpr std::uint32_t kRccAhb1Enr = 0x30;
constexpr std::uint32_t kFlashIfBase = 0x40023C00;
constexpr std::uint32_t kPwrBase = 0x40007000;
constexpr std::uint32_t kGpioABase = 0x40020000;
constexpr std::uint32_t kGpioCBase = 0x40020800;
constexpr std::uint32_t kTim1Base = 0x40010000;
constexpr std::uint32_t kTim2Base = 0x40000000;
constexpr std::uint32_t kTim3Base = 0x40000400;
constexpr std::uint32_t kTim5Base = 0x40000C00;
constexpr std::uint32_t kDma2Base = 0x40026400;
constexpr std::uint32_t kIwdgBase = 0x40003000;
constexpr std::uint32_t kDbgmcuBase = 0xE0042000;
constexpr std::uint32_t kUniqueIdPage = 0x1FFF7000;
constexpr std::uint32_t kGpioBBase = 0x40020400;
constexpr std::uint32_t kGpioModer = 0x00;
constexpr std::uint32_t kGpioPupdr = 0x0C;
constexpr std::uint32_t kGpioIdr = 0x10;
constexpr std::uint32_t kScsBase = 0xE000E000;
constexpr std::uint32_t kScbVtor = 0xD08;
constexpr std::uint32_t kScbCpacr = 0xD88;

std::vector<std::uint8_t> read_file(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) return {};
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

template <typename T>
T get(const std::vector<std::uint8_t>& b, std::size_t at) {
  T v{};
  if (at + sizeof v <= b.size()) std::memcpy(&v, b.data() + at, sizeof v);
  return v;
}

/// The loadable segments of a 32-bit little-endian ARM ELF (at their load
/// addresses) and one symbol's value.
struct Elf {
  struct Segment {
    std::uint32_t address;
    std::vector<std::uint8_t> bytes;
  };
  std::vector<Segment> segments;
  std::vector<std::uint8_t> file;

  static std::optional<Elf> load(const std::string& path) {
    Elf elf;
    elf.file = read_file(path);
    const auto& b = elf.file;
    if (b.size() < 52 ||
        std::memcmp(b.data(),
                    "\x7f"
                    "ELF",
                    4) != 0 ||
        b[4] != 1 || b[5] != 1)
      return std::nullopt;
    const auto phoff = get<std::uint32_t>(b, 28);
    const auto phentsize = get<std::uint16_t>(b, 42);
    const auto phnum = get<std::uint16_t>(b, 44);
    for (std::uint16_t i = 0; i < phnum; ++i) {
      const std::size_t ph = phoff + static_cast<std::size_t>(i) * phentsize;
      if (get<std::uint32_t>(b, ph) != 1) continue;  // PT_LOAD
      const auto offset = get<std::uint32_t>(b, ph + 4);
      const auto paddr = get<std::uint32_t>(b, ph + 12);
      const auto filesz = get<std::uint32_t>(b, ph + 16);
      if (filesz == 0 || offset + filesz > b.size()) continue;
      elf.segments.push_back(
          {paddr, std::vector<std::uint8_t>(b.begin() + offset, b.begin() + offset + filesz)});
    }
    return elf;
  }

  /// The value of symbol `name` (mangled), or 0.
  std::uint32_t symbol(const std::string& name) const {
    const auto& b = file;
    const auto shoff = get<std::uint32_t>(b, 32);
    const auto shentsize = get<std::uint16_t>(b, 46);
    const auto shnum = get<std::uint16_t>(b, 48);
    for (std::uint16_t i = 0; i < shnum; ++i) {
      const std::size_t sh = shoff + static_cast<std::size_t>(i) * shentsize;
      if (get<std::uint32_t>(b, sh + 4) != 2) continue;  // SHT_SYMTAB
      const auto offset = get<std::uint32_t>(b, sh + 16);
      const auto size = get<std::uint32_t>(b, sh + 20);
      const auto link = get<std::uint32_t>(b, sh + 24);
      const std::size_t strsh = shoff + static_cast<std::size_t>(link) * shentsize;
      const auto stroff = get<std::uint32_t>(b, strsh + 16);
      for (std::uint32_t s = 0; s + 16 <= size; s += 16) {
        const auto name_at = get<std::uint32_t>(b, offset + s);
        const char* n = reinterpret_cast<const char*>(b.data() + stroff + name_at);
        if (name == n) return get<std::uint32_t>(b, offset + s + 4);
      }
    }
    return 0;
  }
};

/// The chip: flash, SRAM, the modelled registers (RM0090 reset values), and why it stopped.
class Chip {
 public:
  Chip() {
    EXPECT_EQ(uc_open(UC_ARCH_ARM, static_cast<uc_mode>(UC_MODE_THUMB | UC_MODE_MCLASS), &uc_),
              UC_ERR_OK);
    EXPECT_EQ(uc_ctl_set_cpu_model(uc_, UC_CPU_ARM_CORTEX_M4), UC_ERR_OK);
    EXPECT_EQ(uc_mem_map(uc_, kFlashBase, kFlashSize, UC_PROT_READ | UC_PROT_EXEC), UC_ERR_OK);
    EXPECT_EQ(uc_mem_map(uc_, kSramBase, kSramSize, UC_PROT_ALL), UC_ERR_OK);
    const std::vector<std::uint8_t> erased(kFlashSize, 0xFF);
    uc_mem_write(uc_, kFlashBase, erased.data(), erased.size());
    // SRAM after power-on: not zero, not a valid record.
    std::vector<std::uint8_t> sram(kSramSize);
    for (std::size_t i = 0; i < sram.size(); ++i) sram[i] = static_cast<std::uint8_t>(i * 37 + 11);
    uc_mem_write(uc_, kSramBase, sram.data(), sram.size());
    model_registers();
    for (const std::uint32_t block :
         {kRccBase, kFlashIfBase, kPwrBase, kGpioABase, kGpioBBase, kGpioCBase, kTim1Base,
          kTim2Base, kTim3Base, kTim5Base, kDma2Base, kIwdgBase, kDbgmcuBase})
      map_region(block, 0x400);
    map_region(kScsBase, 0x1000);
    map_region(kUniqueIdPage, 0x1000);
    uc_hook hook;
    uc_hook_add(uc_, &hook, UC_HOOK_MEM_UNMAPPED, reinterpret_cast<void*>(&Chip::unmapped), this, 1,
                0);
  }
  ~Chip() { uc_close(uc_); }
  Chip(const Chip&) = delete;
  Chip& operator=(const Chip&) = delete;

  void write(std::uint32_t address, const std::vector<std::uint8_t>& bytes) {
    ASSERT_EQ(uc_mem_write(uc_, address, bytes.data(), bytes.size()), UC_ERR_OK);
  }
  void write_word(std::uint32_t address, std::uint32_t value) {
    ASSERT_EQ(uc_mem_write(uc_, address, &value, 4), UC_ERR_OK);
  }
  std::uint32_t read_word(std::uint32_t address) {
    std::uint32_t v = 0;
    uc_mem_read(uc_, address, &v, 4);
    return v;
  }
  void stop_at(std::uint32_t address, const char* name) {
    stops_.push_back({address & ~1u, name});
    uc_hook hook;
    uc_hook_add(uc_, &hook, UC_HOOK_CODE, reinterpret_cast<void*>(&Chip::on_code), this,
                address & ~1u, address & ~1u);
  }

  /// Resets the core (SP and PC from the vector table at 0) and runs to a stop.
  std::string run() {
    const std::uint32_t sp = read_word(kFlashBase);
    const std::uint32_t pc = read_word(kFlashBase + 4);
    uc_reg_write(uc_, UC_ARM_REG_SP, &sp);
    return go(pc);
  }
  /// Runs on from where the last stop was.
  std::string resume() { return go(reg(UC_ARM_REG_PC)); }

  std::uint32_t reg(int r) {
    std::uint32_t v = 0;
    uc_reg_read(uc_, r, &v);
    return v;
  }
  /// A modelled peripheral register's value.
  std::uint32_t io(std::uint32_t address) const { return regs_.at(address); }
  /// Every value written to `address`, in order.
  std::vector<std::uint32_t> writes_to(std::uint32_t address) const {
    std::vector<std::uint32_t> out;
    for (const auto& [a, v] : writes_)
      if (a == address) out.push_back(v);
    return out;
  }

  bool recovery_pin_high = false;

 private:
  std::string go(std::uint32_t pc) {
    skip_stop_ = pc & ~1u;
    stopped_at_ = "no stop";
    const uc_err err = uc_emu_start(uc_, pc | 1u, 0, 0, 400'000'000);
    if (!error_.empty()) return "error: " + error_;
    if (err != UC_ERR_OK) return std::string("error: unicorn: ") + uc_strerror(err);
    return stopped_at_;
  }

  /// One MMIO region: the callbacks get offsets into it.
  struct Region {
    Chip* chip;
    std::uint32_t base;
  };
  void map_region(std::uint32_t base, std::uint32_t size) {
    regions_.push_back(std::make_unique<Region>(Region{this, base}));
    Region* r = regions_.back().get();
    EXPECT_EQ(uc_mmio_map(uc_, base, size, &Chip::mmio_read, r, &Chip::mmio_write, r), UC_ERR_OK);
  }

  void model_registers() {
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
    block(kPwrBase, 0x04);
    for (const std::uint32_t gpio : {kGpioABase, kGpioBBase, kGpioCBase}) block(gpio, 0x24);
    regs_[kGpioABase + 0x00] = 0xA8000000;
    regs_[kGpioABase + 0x08] = 0x0C000000;
    regs_[kGpioABase + 0x0C] = 0x64000000;
    regs_[kGpioBBase + 0x00] = 0x00000280;
    regs_[kGpioBBase + 0x08] = 0x000000C0;
    regs_[kGpioBBase + 0x0C] = 0x00000100;
    for (const std::uint32_t tim : {kTim1Base, kTim2Base, kTim3Base, kTim5Base}) block(tim, 0x50);
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
    regs_[kUniqueIdPage + 0xA10] = 0x00470031;
    regs_[kUniqueIdPage + 0xA14] = 0x31385119;
    regs_[kUniqueIdPage + 0xA18] = 0x32363734;
  }

  /// What reading `address` shows (the register, plus the hardware's status bits).
  std::uint32_t observe(std::uint32_t address) {
    std::uint32_t v = regs_.at(address);
    if (address == kRccBase + 0x00) {  // CR: each oscillator / the PLL ready once on
      if (v & (1u << 0)) v |= 1u << 1;
      if (v & (1u << 16)) v |= 1u << 17;
      if (v & (1u << 24)) v |= 1u << 25;
    } else if (address == kRccBase + 0x08) {  // CFGR: SWS follows SW
      v = (v & ~0xCu) | ((v & 0x3u) << 2);
    } else if (address == kGpioBBase + kGpioIdr) {  // PB2: the recovery jumper, else pulled down
      v = recovery_pin_high ? (1u << 2) : 0u;
    } else if (address == kGpioABase + kGpioIdr || address == kGpioCBase + kGpioIdr) {
      v = 0;
    }
    return v;
  }

  void store(std::uint32_t address, std::uint32_t value) {
    writes_.push_back({address, value});
    const std::uint32_t offset = address & 0x3FFu;
    const std::uint32_t base = address & ~0x3FFu;
    if (address == kRccBase + 0x74 && (value & (1u << 24)) != 0) {  // CSR.RMVF
      regs_[address] = regs_[address] & 0x00FFFFFFu;
      return;
    }
    if ((base == kGpioABase || base == kGpioBBase || base == kGpioCBase) && offset == 0x18) {
      // BSRR: set bits win over reset bits; ODR changes, BSRR reads 0.
      std::uint32_t& odr = regs_[base + 0x14];
      odr = (odr & ~(value >> 16)) | (value & 0xFFFFu);
      return;
    }
    regs_[address] = value;
  }

  bool clocked(std::uint32_t address) const {
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
    return true;
  }

  void unmodelled(const char* what, std::uint64_t address) {
    char buffer[96];
    std::snprintf(buffer, sizeof buffer, "%s of 0x%08llx (not modelled) at pc 0x%08x", what,
                  static_cast<unsigned long long>(address), reg(UC_ARM_REG_PC));
    if (error_.empty()) error_ = buffer;
    uc_emu_stop(uc_);
  }

  bool check(std::uint32_t word, const char* what, std::uint32_t address) {
    if (regs_.count(word) == 0) {
      unmodelled(what, address);
      return false;
    }
    if (!clocked(word)) {
      unmodelled(what, address);  // a peripheral whose clock is off ignores the bus
      return false;
    }
    return true;
  }

  static std::uint64_t mmio_read(uc_engine*, std::uint64_t offset, unsigned size, void* user) {
    const auto* region = static_cast<const Region*>(user);
    Chip* chip = region->chip;
    const std::uint32_t address = region->base + static_cast<std::uint32_t>(offset);
    const std::uint32_t word = address & ~3u;
    if (!chip->check(word, "read", address)) return 0;
    const std::uint32_t v = chip->observe(word) >> (8 * (address & 3u));
    return size == 4 ? v : v & ((1u << (8 * size)) - 1u);
  }

  static void mmio_write(uc_engine*, std::uint64_t offset, unsigned size, std::uint64_t value,
                         void* user) {
    const auto* region = static_cast<const Region*>(user);
    Chip* chip = region->chip;
    const std::uint32_t address = region->base + static_cast<std::uint32_t>(offset);
    const std::uint32_t word = address & ~3u;
    if (!chip->check(word, "write", address)) return;
    std::uint32_t v = static_cast<std::uint32_t>(value);
    if (size != 4) {  // a byte or half-word: the other lanes keep their value
      const std::uint32_t shift = 8 * (address & 3u);
      const std::uint32_t mask = ((size == 1 ? 0xFFu : 0xFFFFu)) << shift;
      v = (chip->regs_.at(word) & ~mask) | ((v << shift) & mask);
    }
    chip->store(word, v);
  }

  static bool unmapped(uc_engine*, uc_mem_type type, std::uint64_t address, int, std::int64_t,
                       void* user) {
    static_cast<Chip*>(user)->unmodelled(type == UC_MEM_WRITE_UNMAPPED   ? "write"
                                         : type == UC_MEM_FETCH_UNMAPPED ? "fetch"
                                                                         : "read",
                                         address);
    return false;
  }
  static void on_code(uc_engine* uc, std::uint64_t address, std::uint32_t, void* user) {
    auto* chip = static_cast<Chip*>(user);
    if (address == chip->skip_stop_) {  // resuming from this stop
      chip->skip_stop_ = 0;
      return;
    }
    for (const auto& [at, name] : chip->stops_)
      if (at == address) chip->stopped_at_ = name;
    uc_emu_stop(uc);
  }

  uc_engine* uc_ = nullptr;
  std::map<std::uint32_t, std::uint32_t> regs_;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> writes_;
  std::vector<std::pair<std::uint32_t, std::string>> stops_;
  std::uint32_t skip_stop_ = 0;
  std::vector<std::unique_ptr<Region>> regions_;
  std::string stopped_at_ = "no stop";
  std::string error_;
};

class BootloaderEmu : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto elf = Elf::load(FLUTTERSCAN_BOOTLOADER_ELF);
    image_ = read_file(FLUTTERSCAN_FW_STM32F405_BIN);
    if (!elf || image_.empty())
      GTEST_SKIP() << "no bootloader ELF / application image (make fw-stm32f405 builds them)";
    bootloader_ = *elf;
    bootloader_main_ = bootloader_.symbol("_Z15bootloader_mainv");
    ASSERT_NE(bootloader_main_, 0u);
    app_reset_ = get<std::uint32_t>(image_, kAppVectorTableOffset + 4);
    app_sp_ = get<std::uint32_t>(image_, kAppVectorTableOffset);
  }

  /// A chip with the bootloader and `app` in flash, stopping at the
  /// application's reset handler or at bootloader_main.
  void flash(Chip& chip, const std::vector<std::uint8_t>& app) {
    for (const auto& s : bootloader_.segments) chip.write(s.address, s.bytes);
    if (!app.empty()) chip.write(kAppBase, app);
    chip.stop_at(app_reset_, "application");
    chip.stop_at(bootloader_main_, "dfu");
  }

  Elf bootloader_;
  std::vector<std::uint8_t> image_;
  std::uint32_t bootloader_main_ = 0;
  std::uint32_t app_reset_ = 0;
  std::uint32_t app_sp_ = 0;
};

TEST_F(BootloaderEmu, AGoodImageIsStartedThroughItsVectorTable) {
  Chip chip;
  flash(chip, image_);
  ASSERT_EQ(chip.run(), "application");
  EXPECT_EQ(chip.reg(UC_ARM_REG_PC) | 1u, app_reset_);
  EXPECT_EQ(chip.reg(UC_ARM_REG_MSP), app_sp_);
  EXPECT_EQ(chip.io(kScsBase + kScbVtor), kAppBase + kAppVectorTableOffset);
  // The recovery pin was read and everything put back as reset left it.
  EXPECT_EQ(chip.io(kRccBase + kRccAhb1Enr), 0x00100000u);
  EXPECT_EQ(chip.io(kGpioBBase + kGpioPupdr), 0x00000100u);
  // This start is on trial: one unconfirmed start in the record.
  BootRecord record{};
  record.magic = chip.read_word(0x20000004);
  record.unconfirmed_starts = chip.read_word(0x20000008);
  record.check = chip.read_word(0x2000000C);
  EXPECT_EQ(unconfirmed_starts(record), 1u);
  EXPECT_EQ(chip.read_word(0x20000000), 0u);  // the hand-off word
}

TEST_F(BootloaderEmu, EmptyOrCorruptImagesStayInDfuMode) {
  {
    Chip chip;
    flash(chip, {});
    EXPECT_EQ(chip.run(), "dfu");
  }
  auto corrupt = image_;
  corrupt[corrupt.size() / 2] ^= 0x01;
  Chip chip;
  flash(chip, corrupt);
  EXPECT_EQ(chip.run(), "dfu");
}

TEST_F(BootloaderEmu, AResetVectorOutsideTheImageStaysInDfuMode) {
  auto image = image_;
  const std::uint32_t into_bootloader = 0x08000101;
  std::memcpy(image.data() + kAppVectorTableOffset + 4, &into_bootloader, 4);
  ASSERT_TRUE(stamp_image(image));  // CRC-valid
  Chip chip;
  flash(chip, image);
  EXPECT_EQ(chip.run(), "dfu");
}

TEST_F(BootloaderEmu, TheHandOffWordTheRecoveryPinAndUnconfirmedStartsKeepDfuMode) {
  {
    Chip chip;
    flash(chip, image_);
    chip.write_word(0x20000000, 0xB007DF11);  // EnterBootloader / DFU_DETACH
    EXPECT_EQ(chip.run(), "dfu");
    EXPECT_EQ(chip.read_word(0x20000000), 0u);  // once
  }
  {
    Chip chip;
    flash(chip, image_);
    chip.recovery_pin_high = true;
    EXPECT_EQ(chip.run(), "dfu");
  }
  for (std::uint32_t starts : {2u, 3u}) {
    Chip chip;
    flash(chip, image_);
    const BootRecord r = make_boot_record(starts);
    chip.write_word(0x20000004, r.magic);
    chip.write_word(0x20000008, r.unconfirmed_starts);
    chip.write_word(0x2000000C, r.check);
    EXPECT_EQ(chip.run(), starts < kMaxUnconfirmedStarts ? "application" : "dfu") << starts;
  }
}

// Reset -> bootloader -> image check -> application: the application's own
// start-up (C runtime, clocks from HSE through the PLL, the port's GPIO,
// timers, DMA, NVIC, the controller loading its config from both flash copies,
// the watchdog, SysTick) runs on the modelled chip up to the USB driver's init.
TEST_F(BootloaderEmu, ResetRunsTheBootloaderThenTheApplicationsStartUpWithClocksUp) {
  const auto app = Elf::load(FLUTTERSCAN_FW_STM32F405_ELF);
  if (!app) GTEST_SKIP() << "no application ELF";
  const std::uint32_t usb_init =
      app->symbol("_ZN11flutterscan8firmware7stm32f411OtgFsDevice4initEm");
  ASSERT_NE(usb_init, 0u);
  Chip chip;
  flash(chip, image_);
  chip.stop_at(usb_init, "usb init");
  ASSERT_EQ(chip.run(), "application");
  ASSERT_EQ(chip.resume(), "usb init");
  // Clocks (RM0090 6.3): HSE on, PLL M 8, N 336, P 2, Q 7 from HSE, SYSCLK = PLL,
  // APB1 /4, APB2 /2, 5 wait states.
  EXPECT_NE(chip.io(kRccBase + 0x00) & (1u << 16), 0u);
  EXPECT_NE(chip.io(kRccBase + 0x00) & (1u << 24), 0u);
  const std::uint32_t pllcfgr = chip.io(kRccBase + 0x04);
  EXPECT_EQ(pllcfgr & 0x3Fu, 8u);
  EXPECT_EQ((pllcfgr >> 6) & 0x1FFu, 336u);
  EXPECT_EQ((pllcfgr >> 16) & 0x3u, 0u);  // P = 2
  EXPECT_EQ((pllcfgr >> 24) & 0xFu, 7u);
  EXPECT_NE(pllcfgr & (1u << 22), 0u);             // source HSE
  EXPECT_EQ(chip.io(kRccBase + 0x08) & 0x3u, 2u);  // SW = PLL
  EXPECT_EQ(chip.io(kFlashIfBase) & 0xFu, 5u);
  // LEDs: the board config's three, PC0..PC2, outputs driven low; no slot
  // table running or pre-armed.
  EXPECT_EQ(chip.io(kGpioCBase + kGpioModer) & 0x3Fu, 0x15u);
  EXPECT_EQ(chip.io(kGpioCBase + 0x14) & 0x7u, 0u);
  const auto bsrr = chip.writes_to(kGpioCBase + 0x18);
  ASSERT_FALSE(bsrr.empty());
  EXPECT_EQ(bsrr.front() & 0xFFFFu, 0u);          // the first LED write sets nothing
  EXPECT_EQ(chip.io(kTim1Base + 0x00) & 1u, 0u);  // TIM1 stopped
  EXPECT_EQ(chip.io(kTim1Base + 0x08), 0u);       // no trigger: nothing pre-armed at boot
  // The watchdog started (IWDG_KR 0xCCCC), TIM2 (the clock) running.
  const auto kr = chip.writes_to(kIwdgBase + 0x00);
  EXPECT_NE(std::find(kr.begin(), kr.end(), 0xCCCCu), kr.end());
  EXPECT_EQ(chip.io(kTim2Base + 0x00) & 1u, 1u);
}

}  // namespace
}  // namespace flutterscan::firmware::emu
